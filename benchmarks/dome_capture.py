"""The reduced rendered dome capture into capture stores, timed. Prints JSON.

A ``dome-run`` of each material (default: the colour checker and the Lego bricks) at the reduced
size ``--stage-positions`` x ``--leds`` x ``--rgb-cameras`` (default 2 x 24 x 3, and the spectral
camera) at ``--texels`` (64: 264 x 264 px frames) and ``--spp`` (default the capture's own,
:data:`twin.dome.programs.DEFAULT_SPP`), in this process (renders on every core). Reports per
material the wall time, the CPU time, the frames and renders, the time per render and frame,
the store's size on disk and the estimated time of the same capture on the real rig (the plan's
timing). A capture of one stage position, LED and RGB camera at the same frame size and spp
first fills Dr.Jit's kernel cache, so the timings do not pay for compiling the kernels.

Run: .venv/bin/python -m benchmarks.dome_capture [--materials lego ...] [--out DIR]
"""

from __future__ import annotations

import argparse
import json
import resource
import tempfile
import time
from pathlib import Path

from benchmarks.common import (
    add_dome_size_arguments,
    dome_size_settings,
    machine_description,
    peak_rss_mib,
)
from twin.dome.programs import DomeCaptureSize, dome_run_program
from twin.studies.sweep_points import storage_mb


def _cpu_s() -> float:
    usage = resource.getrusage(resource.RUSAGE_SELF)
    return usage.ru_utime + usage.ru_stime


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__)
    parser.add_argument("--materials", nargs="+", default=["colorchecker16", "lego"])
    add_dome_size_arguments(parser)
    parser.add_argument("--seed", type=int, default=0)
    parser.add_argument("--out", type=Path, default=None, help="Keep the stores here.")
    arguments = parser.parse_args()
    size = DomeCaptureSize(**dome_size_settings(arguments))
    folder = arguments.out or Path(tempfile.mkdtemp(prefix="dome_capture_"))
    folder.mkdir(parents=True, exist_ok=True)
    warm = DomeCaptureSize(1, 1, 1, size.texels, size.spp)
    dome_run_program(arguments.materials[0], size=warm).run(folder / "warm.capture.zarr")
    results = {}
    for material in arguments.materials:
        program = dome_run_program(material, size=size, seed=arguments.seed)
        plan = program.dry_run()
        started, cpu = time.perf_counter(), _cpu_s()
        store = program.run(folder / f"{material}.capture.zarr")
        wall_s = time.perf_counter() - started
        results[material] = {
            "complete": store.complete,
            "wall_s": round(wall_s, 1),
            "cpu_s": round(_cpu_s() - cpu, 1),
            "frames": plan["steps"],
            "renders": plan["renders"],
            "s_per_render": round(wall_s / plan["renders"], 2),
            "frame_size": plan["frame_size"],
            "store_mb": round(storage_mb(store.path), 1),
            "rig_estimate_s": round(plan["estimated_duration_s"], 1),
        }
    print(
        json.dumps(
            {
                "machine": machine_description(),
                "size": {
                    "stage_positions": size.stage_positions,
                    "leds": size.leds,
                    "rgb_cameras": size.rgb_cameras,
                    "texels": size.texels,
                    "spp": size.spp,
                },
                "seed": arguments.seed,
                "materials": results,
                "peak_rss_mib": peak_rss_mib(),
                "stores": str(folder),
            },
            indent=2,
        )
    )


if __name__ == "__main__":
    main()
