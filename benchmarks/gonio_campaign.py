"""Per-pair time of a full gonioreflectometer campaign, split by stage, and its projection.
Prints JSON.

The measurement run of the colour checker over Sattler's 81 x 81 directions (the pairs the rig
reaches) at ``--pixels``: its store is made for the whole plan, the dark frames and the white
standard are captured, then ``--pairs`` direction pairs spread evenly over the plan (33 frames
each), the first of them apart (it compiles the render kernel). Every stage is timed where it is
called: the renderer (``GonioScene.part_rates``), the sensor model (``Sensor.capture``) and the
capture store (frames, index and flags); "other" is the rest of a step (devices, lamp monitor,
the signal of each band, the session). Wall time and CPU time of the whole process (Dr.Jit's
and the sensor's threads included), per pair; the machine's load average before and after. The
projection is the darks and white plus ``--campaign`` pairs at the measured mean.

The timers are put around whichever of those functions the code has, so the script also times
earlier versions of spectwin (one render per lamp part, ``gonio_part_rates``; ``write_frame``
per frame).

Run: .venv/bin/python -m benchmarks.gonio_campaign [--pairs 300] [--pixels 256] [--spp N]
"""

from __future__ import annotations

import argparse
import json
import os
import tempfile
import time
from collections import defaultdict
from pathlib import Path

import numpy as np

from benchmarks.common import machine_description, peak_rss_mib, per_unit, timed_stages
from hwbridge import store as store_module
from hwbridge.session import SessionSettings, capture_steps, locked_session_store
from recon.calibration.spectral import HMI_FLICKER_PERIOD_S
from twin.gonio import render as render_module
from twin.gonio import signals as signals_module
from twin.gonio.capture import gonio_measurement_program, gonio_pairs
from twin.render.variant import activate
from twin.rigs.hemisphere import SATTLER_RINGS
from twin.rigs.rig_config import load_rig
from twin.sensor import model as sensor_module

_STAGES = {
    "render": [
        (getattr(render_module, "GonioScene", None), "part_rates"),
        (signals_module, "gonio_part_rates"),
    ],
    "sensor": [(sensor_module.Sensor, "capture")],
    "store": [
        (store_module.CaptureStore, name)
        for name in ("write_frame", "write_frames", "write_index", "mark_done")
    ],
}


def _phase(store, steps, program, seed) -> dict[str, dict[str, float]]:
    """Capture ``steps`` with ``program``'s devices; wall and CPU seconds in total and per
    stage."""
    devices = program.devices(seed, steps)
    return timed_stages(_STAGES, lambda: capture_steps(store, steps, devices))


def main() -> None:
    parser = argparse.ArgumentParser()
    parser.add_argument("--pairs", type=int, default=300, help="direction pairs to capture")
    parser.add_argument("--pixels", type=int, default=256)
    parser.add_argument("--spp", type=int, default=None, help="default: the capture's default")
    parser.add_argument("--campaign", type=int, default=6561, help="pairs to project to")
    parser.add_argument("--out", type=Path, default=None, help="keep the store here")
    arguments = parser.parse_args()
    report = activate()
    load_before = os.getloadavg()
    config = load_rig("gonio")
    pairs = gonio_pairs(config, SATTLER_RINGS)
    exposures = np.full(33, 6 * HMI_FLICKER_PERIOD_S)
    options = {} if arguments.spp is None else {"spp": arguments.spp}
    program = gonio_measurement_program(
        exposures, pairs=pairs, pixels=arguments.pixels, seed=0, **options
    )
    plan = program.plan
    root = arguments.out or Path(tempfile.mkdtemp(prefix="spectwin-campaign-"))
    started = time.perf_counter()
    settings = SessionSettings(rig=program.rig, backend="sim", seed=0)
    with locked_session_store(
        root / "campaign.capture.zarr", plan, program.devices(), settings
    ) as store:
        create_s = time.perf_counter() - started
        by_view: dict[int, list[int]] = defaultdict(list)
        for step, settings in enumerate(plan):
            by_view[settings.get("view_id", -1)].append(step)
        white = program.rig.white_view_id
        chosen = np.linspace(0, len(pairs.poses) - 1, arguments.pairs + 1).round().astype(int)
        before = _phase(store, by_view[-1] + by_view[white], program, 0)
        first = _phase(store, by_view[int(chosen[0])], program, 0)
        steady = _phase(store, [s for view in chosen[1:] for s in by_view[int(view)]], program, 0)
    mean = steady["total"]["wall_s"] / arguments.pairs
    projection_s = before["total"]["wall_s"] + arguments.campaign * mean
    results = {
        "machine": machine_description(),
        "variant": report.as_dict(),
        "load_average_before": [round(value, 2) for value in load_before],
        "load_average_after": [round(value, 2) for value in os.getloadavg()],
        "pixels": arguments.pixels,
        "spp": program.rig.spp,
        "plan_steps": len(plan),
        "reachable_pairs": len(pairs.poses),
        "store_creation_s": round(create_s, 2),
        "darks_and_white": {
            "frames": len(by_view[-1] + by_view[white]),
            **per_unit(before, 1),
        },
        "first_pair": per_unit(first, 1),
        "pairs_timed": arguments.pairs,
        "per_pair": per_unit(steady, arguments.pairs),
        "campaign_pairs": arguments.campaign,
        "campaign_projected_h": round(projection_s / 3600, 3),
        "campaign_projected_cpu_h": round(
            (
                before["total"]["cpu_s"]
                + arguments.campaign * steady["total"]["cpu_s"] / arguments.pairs
            )
            / 3600,
            3,
        ),
        "peak_rss_mib": peak_rss_mib(),
    }
    print(json.dumps(results, indent=2))


if __name__ == "__main__":
    main()
