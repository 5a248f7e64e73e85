"""A gonio measurement run and its processing, serially and on a Dask LocalCluster. Prints JSON.

The run of the demo's 20 direction pairs (``DEMO_RINGS``) at ``--pixels`` and ``--spp``, band
exposures of 0.4 s (6 HMI flicker periods), captured in one process and on a ``LocalCluster`` of
``--workers`` one-thread worker processes (:mod:`twin.devices.cluster`); then processed both ways
into BTFs of ``--texels`` (a synthetic linear calibration: the timing does not depend on it).
Reports wall times, frames per second, the speed-up, the CPU time of the capture (this process
serially, the workers on the cluster) and the cores it kept busy on average, and whether the
frames, the index (but the wall-clock timestamps) and the BTFs are bit-identical. One render
before the timings fills Dr.Jit's kernel cache, so neither way pays for compiling the kernels.

Run: .venv/bin/python -m benchmarks.distributed_capture [--pixels N] [--workers N] [--out DIR]
"""

from __future__ import annotations

import argparse
import json
import resource
import tempfile
import time
from pathlib import Path

import numpy as np

from benchmarks.common import machine_description, timed
from hwbridge.store import CaptureStore
from recon.calibration.gonio import GonioCalibration
from recon.calibration.spectral import HMI_FLICKER_PERIOD_S
from twin.components.lctf import LiquidCrystalTunableFilter
from twin.devices.cluster import dask_client, run_process
from twin.gonio.capture import CAMERA_ID, actual_poses, gonio_pairs, run_gonio_measurement
from twin.gonio.render import gonio_part_rates
from twin.materials import load_material
from twin.render.variant import activate
from twin.rigs.rig_config import load_rig
from twin.studies.demo import DEMO_RINGS


def _cpu_s() -> float:
    """CPU time of this process so far (user and system), s."""
    usage = resource.getrusage(resource.RUSAGE_SELF)
    return usage.ru_utime + usage.ru_stime


def _same_capture(a: CaptureStore, b: CaptureStore) -> bool:
    index_a, index_b = a.index(CAMERA_ID), b.index(CAMERA_ID)
    return np.array_equal(a.frames(CAMERA_ID)[:], b.frames(CAMERA_ID)[:]) and all(
        np.array_equal(index_a[name], index_b[name], equal_nan=index_a[name].dtype.kind == "f")
        for name in index_a
        if name != "timestamp"
    )


def main() -> None:
    parser = argparse.ArgumentParser()
    parser.add_argument("--pixels", type=int, default=256)
    parser.add_argument("--spp", type=int, default=64)
    parser.add_argument("--texels", type=int, default=64)
    parser.add_argument("--workers", type=int, default=2)
    parser.add_argument("--out", type=Path, default=None, help="keep the stores here")
    arguments = parser.parse_args()
    root = arguments.out or Path(tempfile.mkdtemp(prefix="spectwin-bench-"))
    config = load_rig("gonio")
    pairs = gonio_pairs(config, DEMO_RINGS)
    bands = np.asarray(LiquidCrystalTunableFilter.varispec(config.camera.filter).band_centres_nm)
    exposures = np.full(bands.size, 6 * HMI_FLICKER_PERIOD_S)
    calibration = GonioCalibration.identity(exposures, bands, HMI_FLICKER_PERIOD_S)
    results: dict[str, object] = {
        "machine": machine_description(),
        "variant": activate().as_dict(),
        "pairs": len(pairs.poses),
        "pixels": arguments.pixels,
        "spp": arguments.spp,
        "workers": arguments.workers,
    }
    gonio_part_rates(
        config,
        actual_poses(config, pairs.poses[:1], 0)[0],
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
    started = time.perf_counter()
    with dask_client(arguments.workers) as client:
        start_s = round(time.perf_counter() - started, 2)
        workers_cpu_s = client.run(_cpu_s)
        cluster, cluster_s = timed(lambda: capture("cluster", client))
        cluster_cpu_s = sum(client.run(_cpu_s).values()) - sum(workers_cpu_s.values())
        cluster_btf, cluster_process_s = timed(lambda: process("cluster", client))
    frames = serial.frames(CAMERA_ID).shape[0]
    results["capture"] = {
        "frames": frames,
        "serial_s": serial_s,
        "serial_frames_per_s": round(frames / serial_s, 2),
        "serial_cpu_s": round(serial_cpu_s, 1),
        "serial_cores_busy": round(serial_cpu_s / serial_s, 2),
        "cluster_start_s": start_s,
        "cluster_s": cluster_s,
        "cluster_frames_per_s": round(frames / cluster_s, 2),
        "cluster_workers_cpu_s": round(cluster_cpu_s, 1),
        "cluster_cores_busy": round(cluster_cpu_s / cluster_s, 2),
        "speedup": round(serial_s / cluster_s, 2),
        "speedup_with_cluster_start": round(serial_s / (cluster_s + start_s), 2),
        "bit_identical": _same_capture(serial, cluster),
    }
    results["process"] = {
        "texels": arguments.texels,
        "serial_s": serial_process_s,
        "cluster_s": cluster_process_s,
        "speedup": round(serial_process_s / cluster_process_s, 2),
        "bit_identical": bool(
            np.array_equal(
                serial_btf.reflectance(allow_incomplete=True)[:],
                cluster_btf.reflectance(allow_incomplete=True)[:],
                equal_nan=True,
            )
        ),
    }
    print(json.dumps(results, indent=2))


if __name__ == "__main__":
    main()
