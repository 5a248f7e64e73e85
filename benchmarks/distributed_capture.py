"""A gonio measurement run and its processing, serially and on Dask LocalClusters of 1, 2, 4, ...
workers. Prints JSON.

``--pairs`` direction pairs spread evenly over Sattler's 81 x 81 sampling (the pairs the rig
reaches) at ``--pixels`` and ``--spp``, 33 bands of 0.4 s (6 HMI flicker periods): captured in
one process, then on a ``LocalCluster`` of each of ``--workers`` one-thread worker processes
(:mod:`twin.devices.cluster`), and processed each way into BTFs of ``--texels`` (a synthetic
linear calibration: the timing does not depend on it). For each worker count: wall time, frames
per second, the speed-up over the serial run, the cluster's start, the CPU time of the workers
and the cores they kept busy, and whether the frames, the index (but the wall-clock timestamps)
and the BTF are bit-identical to the serial ones. One render before the timings fills Dr.Jit's
kernel cache, so no run pays for compiling the kernels. The machine's load average is printed
before and after.

Run on a 16-core machine (about 25 minutes at the defaults on 2 cores):

    .venv/bin/python -m benchmarks.distributed_capture --workers 1 2 4 8 16 --pairs 320
"""

from __future__ import annotations

import argparse
import json
import os
import resource
import shutil
import tempfile
import time
from collections.abc import Iterator
from contextlib import contextmanager
from pathlib import Path

import numpy as np
from distributed import Client, LocalCluster

from benchmarks.common import machine_description, timed
from hwbridge.store import CaptureStore
from recon.calibration.gonio import GonioCalibration
from recon.calibration.spectral import HMI_FLICKER_PERIOD_S
from twin.components.lctf import LiquidCrystalTunableFilter
from twin.devices.cluster import dask_client, run_process
from twin.gonio.capture import CAMERA_ID, GonioPairs, gonio_pairs, run_gonio_measurement
from twin.gonio.render import GONIO_SPP, gonio_part_rates
from twin.materials import load_material
from twin.render.variant import activate
from twin.rigs.hemisphere import SATTLER_RINGS
from twin.rigs.rig_config import load_rig


def _cpu_s() -> float:
    """CPU time of this process so far (user and system, all threads), s."""
    usage = resource.getrusage(resource.RUSAGE_SELF)
    return usage.ru_utime + usage.ru_stime


def _same_capture(a: CaptureStore, b: CaptureStore) -> bool:
    index_a, index_b = a.index(CAMERA_ID), b.index(CAMERA_ID)
    return np.array_equal(a.frames(CAMERA_ID)[:], b.frames(CAMERA_ID)[:]) and all(
        np.array_equal(index_a[name], index_b[name], equal_nan=index_a[name].dtype.kind == "f")
        for name in index_a
        if name != "timestamp"
    )


@contextmanager
def _cluster(workers: int) -> Iterator[Client]:
    """A client of ``workers`` one-thread worker processes (one worker too, which
    :func:`twin.devices.cluster.dask_client` would run serially)."""
    if workers > 1:
        with dask_client(workers) as client:
            yield client
        return
    with LocalCluster(n_workers=1, threads_per_worker=1, dashboard_address=None) as cluster:
        with Client(cluster) as client:
            yield client


def _spread_pairs(config, count: int) -> GonioPairs:
    """``count`` reachable Sattler pairs spread evenly over the sampling."""
    every = gonio_pairs(config, SATTLER_RINGS)
    chosen = np.linspace(0, len(every.poses) - 1, count).round().astype(int)
    pairs = GonioPairs.__new__(GonioPairs)
    pairs.light_dirs, pairs.view_dirs = every.light_dirs[chosen], every.view_dirs[chosen]
    pairs.poses, pairs.skipped = [every.poses[i] for i in chosen], 0
    return pairs


def main() -> None:
    parser = argparse.ArgumentParser()
    parser.add_argument("--pairs", type=int, default=40)
    parser.add_argument("--pixels", type=int, default=256)
    parser.add_argument("--spp", type=int, default=GONIO_SPP)
    parser.add_argument("--texels", type=int, default=64)
    parser.add_argument("--workers", type=int, nargs="+", default=[1, 2])
    parser.add_argument("--out", type=Path, default=None, help="keep the stores here")
    arguments = parser.parse_args()
    root = arguments.out or Path(tempfile.mkdtemp(prefix="spectwin-bench-"))
    config = load_rig("gonio")
    pairs = _spread_pairs(config, arguments.pairs)
    bands = np.asarray(LiquidCrystalTunableFilter.varispec(config.camera.filter).band_centres_nm)
    exposures = np.full(bands.size, 6 * HMI_FLICKER_PERIOD_S)
    calibration = GonioCalibration.identity(exposures, bands, HMI_FLICKER_PERIOD_S)
    results: dict[str, object] = {
        "machine": machine_description(),
        "variant": activate().as_dict(),
        "load_average_before": [round(value, 2) for value in os.getloadavg()],
        "pairs": len(pairs.poses),
        "pixels": arguments.pixels,
        "spp": arguments.spp,
    }
    gonio_part_rates(
        config,
        pairs.poses[0],
        load_material("colorchecker16"),
        pixels=arguments.pixels,
        spp=arguments.spp,
    )

    def capture(name, client):
        return run_gonio_measurement(
            root / f"{name}.capture.zarr",
            exposures,
            pairs=pairs,
            pixels=arguments.pixels,
            spp=arguments.spp,
            client=client,
        )

    def process(name, client):
        return run_process(
            root / "serial.capture.zarr",
            calibration,
            root / f"{name}.btf.zarr",
            texels=arguments.texels,
            client=client,
        )

    cpu_s = _cpu_s()
    serial, serial_s = timed(lambda: capture("serial", None))
    serial_cpu_s = _cpu_s() - cpu_s
    serial_btf, serial_process_s = timed(lambda: process("serial", None))
    frames = serial.frames(CAMERA_ID).shape[0]
    results["frames"] = frames
    results["serial"] = {
        "capture_s": serial_s,
        "frames_per_s": round(frames / serial_s, 2),
        "cpu_s": round(serial_cpu_s, 1),
        "cores_busy": round(serial_cpu_s / serial_s, 2),
        "process_s": serial_process_s,
    }
    reference = serial_btf.reflectance(allow_incomplete=True)[:]
    results["clusters"] = []
    for workers in arguments.workers:
        name = f"workers{workers}"
        started = time.perf_counter()
        with _cluster(workers) as client:
            start_s = round(time.perf_counter() - started, 2)
            before = client.run(_cpu_s)
            cluster, cluster_s = timed(lambda name=name, client=client: capture(name, client))
            busy_s = sum(client.run(_cpu_s).values()) - sum(before.values())
            btf, process_s = timed(lambda name=name, client=client: process(name, client))
        results["clusters"].append(
            {
                "workers": workers,
                "cluster_start_s": start_s,
                "capture_s": cluster_s,
                "frames_per_s": round(frames / cluster_s, 2),
                "speedup": round(serial_s / cluster_s, 2),
                "workers_cpu_s": round(busy_s, 1),
                "cores_busy": round(busy_s / cluster_s, 2),
                "process_s": process_s,
                "process_speedup": round(serial_process_s / process_s, 2),
                "bit_identical_capture": _same_capture(serial, cluster),
                "bit_identical_btf": bool(
                    np.array_equal(
                        reference, btf.reflectance(allow_incomplete=True)[:], equal_nan=True
                    )
                ),
            }
        )
        shutil.rmtree(root / f"{name}.capture.zarr")
        shutil.rmtree(root / f"{name}.btf.zarr")
        print(json.dumps(results["clusters"][-1]), flush=True)
    results["load_average_after"] = [round(value, 2) for value in os.getloadavg()]
    print(json.dumps(results, indent=2))


if __name__ == "__main__":
    main()
