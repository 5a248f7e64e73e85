"""Throughput of a gonio capture campaign and its processing. Prints JSON.

A calibration session, ``calibrate_gonio``, a measurement run of ``--rings`` directions (default:
the demo's 20 pairs) at ``--pixels``, ``process_gonio`` and PCA compression of the BTF, each
timed; captures are reported in frames (images) per second.

Run: .venv/bin/python -m benchmarks.gonio_pipeline [--pixels N] [--texels N] [--out DIR]
"""

from __future__ import annotations

import argparse
import json
import tempfile
from pathlib import Path

import numpy as np

from benchmarks.common import machine_description, peak_rss_mib, timed
from hwbridge.schema import GonioRigAttrs
from recon.btf.compression import compress_btf
from recon.btf.processing import process_gonio
from recon.calibration.gonio import calibrate_gonio
from twin.gonio.capture import CAMERA_ID, run_gonio_calibration, run_gonio_measurement
from twin.render.variant import activate
from twin.studies.demo import DEMO_RINGS


def main() -> None:
    parser = argparse.ArgumentParser()
    parser.add_argument("--pixels", type=int, default=256)
    parser.add_argument("--texels", type=int, default=64)
    parser.add_argument("--out", type=Path, default=None, help="keep the stores here")
    arguments = parser.parse_args()
    report = activate()
    root = arguments.out or Path(tempfile.mkdtemp(prefix="spectwin-bench-"))
    results: dict[str, object] = {"machine": machine_description(), "variant": report.as_dict()}

    calibration_store, seconds = timed(lambda: run_gonio_calibration(root / "cal.capture.zarr"))
    frames = calibration_store.frames(CAMERA_ID).shape[0]
    results["calibration_session"] = {
        "frames": frames,
        "s": seconds,
        "frames_per_s": round(frames / seconds, 1),
    }
    calibration, seconds = timed(lambda: calibrate_gonio(root / "cal.capture.zarr"))
    results["calibrate_s"] = seconds

    run, seconds = timed(
        lambda: run_gonio_measurement(
            root / "run.capture.zarr",
            calibration.planned_exposure_s,
            rings=DEMO_RINGS,
            pixels=arguments.pixels,
        )
    )
    frames = run.frames(CAMERA_ID).shape[0]
    results["measurement_run"] = {
        "pairs": len(run.rig_attrs(GonioRigAttrs).light_dirs),
        "frames": frames,
        "pixels": arguments.pixels,
        "s": seconds,
        "frames_per_s": round(frames / seconds, 1),
    }
    btf, seconds = timed(
        lambda: process_gonio(run, calibration, root / "cc.btf.zarr", texels=arguments.texels)
    )
    results["process"] = {"texels": arguments.texels, "s": seconds}
    reflectance = np.asarray(btf.reflectance())
    for layout in ("per_band", "joint"):
        compressed, seconds = timed(
            lambda layout=layout: compress_btf(reflectance, btf.grid, layout=layout)
        )
        results[f"compress_{layout}"] = {
            "s": seconds,
            "ratio": round(compressed.compression_ratio, 2),
            "shape": list(compressed.shape),
        }
    results["peak_rss_mib"] = peak_rss_mib()
    print(json.dumps(results, indent=2))


if __name__ == "__main__":
    main()
