"""Time of a full-size virtual dome run and calibration, measured on a part and projected.
Prints JSON.

``--program run``: the ``dome-run`` of ``--material`` at the rig's full size (24 stage positions
x 198 LEDs x 11 RGB cameras and the spectral camera) at ``--texels`` (64: 264 x 264 px frames).
Its store is made for the whole plan; then the first stage position is captured: its alignment
frames (all LEDs on), then the frames of the first ``--leds`` LEDs in plan order (all 198 by
default: with ``--led-renders pose`` a stage position's LEDs are rendered in passes of
consecutive LEDs, so a subset shows their cost only where it fills whole passes; at 64 texels
an RGB camera's pass of all 198 LEDs is rendered for its alignment frame, their sum, and so
counts in the alignment's time). The full run is projected as 24 times the alignment plus
``198 / --leds`` times the LEDs' time.

``--program calibration``: the ``dome-calibration`` at full size: every frame that is rendered
(response series, the white standard under every LED, the checkerboard) and ``--dark-share``
of the dark frames (the sensor model alone), the darks projected to all of them.

Every stage is timed where it is called: the renderer (``dome_scene_rates``), the sensor model
(``Sensor.capture``, ``Sensor.dark_frame``) and the capture store; "other" is the rest (devices,
the session). Wall and CPU time of the process, the load average before and after, the peak
memory.

Run: .venv/bin/python -m benchmarks.dome_campaign [--program run|calibration] [--leds 198]
[--texels 64] [--led-renders pose|single] [--material colorchecker16]
"""

from __future__ import annotations

import argparse
import json
import os
import tempfile
import time
from pathlib import Path

from benchmarks.common import machine_description, peak_rss_mib, per_unit, timed_stages
from hwbridge import store as store_module
from hwbridge.session import SessionSettings, capture_steps, locked_session_store
from twin.dome import render as render_module
from twin.dome import signals as signals_module
from twin.dome.programs import DomeCaptureSize, dome_calibration_program, dome_run_program
from twin.render.variant import activate
from twin.sensor import model as sensor_module

_STAGES = {
    "render": [
        (signals_module, "dome_scene_rates"),
        (render_module, "dome_scene_rates"),
    ],
    "sensor": [(sensor_module.Sensor, "capture"), (sensor_module.Sensor, "dark_frame")],
    "store": [
        (store_module.CaptureStore, name)
        for name in ("write_frame", "write_frames", "write_index", "mark_done")
    ],
}


def _rounded(stages: dict[str, dict[str, float]]) -> dict[str, dict[str, float]]:
    return per_unit(stages, 1)


def _timed(program, store, steps) -> dict[str, dict[str, float]]:
    """Capture ``steps`` with ``program``'s devices; wall and CPU seconds per stage."""
    devices = program.devices(0, steps)
    return timed_stages(_STAGES, lambda: capture_steps(store, steps, devices))


def _run(program, store, leds: int) -> dict[str, object]:
    """The first stage position of a full run: its alignment, then ``leds`` LEDs."""
    plan = program.plan
    first = [i for i, step in enumerate(plan) if step.get("view_id") == plan[0]["view_id"]]
    alignment = [i for i in first if plan[i]["kind"] == "alignment"]
    all_leds = list(dict.fromkeys(plan[i]["light_id"] for i in first if i not in alignment))
    chosen = set(all_leds[:leds])
    lit = [i for i in first if plan[i].get("light_id") in chosen]
    aligned = _timed(program, store, alignment)
    each = _timed(program, store, lit)
    positions = program.rig.stage_positions
    scale = len(all_leds) / len(chosen)
    projected_s = positions * (aligned["total"]["wall_s"] + scale * each["total"]["wall_s"])
    projected_cpu_s = positions * (aligned["total"]["cpu_s"] + scale * each["total"]["cpu_s"])
    return {
        "stage_positions": positions,
        "alignment": {"frames": len(alignment), **_rounded(aligned)},
        "leds_timed": len(chosen),
        "led_frames_timed": len(lit),
        "leds": _rounded(each),
        "per_led_s": round(each["total"]["wall_s"] / len(chosen), 3),
        "projected_h": round(projected_s / 3600, 3),
        "projected_cpu_h": round(projected_cpu_s / 3600, 3),
    }


def _calibration(program, store, dark_share: float) -> dict[str, object]:
    """Every rendered frame of a full calibration and ``dark_share`` of its darks."""
    plan = program.plan
    darks = [i for i, step in enumerate(plan) if step["kind"] == "dark"]
    rendered = [i for i, step in enumerate(plan) if step["kind"] != "dark"]
    chosen = darks[:: max(1, round(1 / dark_share))]
    dark = _timed(program, store, chosen)
    lit = _timed(program, store, rendered)
    scale = len(darks) / len(chosen)
    projected_s = scale * dark["total"]["wall_s"] + lit["total"]["wall_s"]
    projected_cpu_s = scale * dark["total"]["cpu_s"] + lit["total"]["cpu_s"]
    return {
        "dark_frames": len(darks),
        "dark_frames_timed": len(chosen),
        "darks": _rounded(dark),
        "rendered_frames": len(rendered),
        "rendered": _rounded(lit),
        "projected_h": round(projected_s / 3600, 3),
        "projected_cpu_h": round(projected_cpu_s / 3600, 3),
    }


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__)
    parser.add_argument("--program", choices=["run", "calibration"], default="run")
    parser.add_argument("--material", default="colorchecker16")
    parser.add_argument("--leds", type=int, default=198, help="run: first LEDs of position 0")
    parser.add_argument("--dark-share", type=float, default=0.05, help="calibration: darks")
    parser.add_argument("--texels", type=int, default=64)
    parser.add_argument("--led-renders", choices=["pose", "single"], default="pose")
    parser.add_argument("--out", type=Path, default=None, help="keep the store here")
    arguments = parser.parse_args()
    report = activate()
    load_before = os.getloadavg()
    size = DomeCaptureSize(texels=arguments.texels, led_renders=arguments.led_renders)
    if arguments.program == "run":
        program = dome_run_program(arguments.material, size=size)
    else:
        program = dome_calibration_program(size=size)
    root = arguments.out or Path(tempfile.mkdtemp(prefix="spectwin-dome-campaign-"))
    started = time.perf_counter()
    with locked_session_store(
        root / f"{arguments.program}.capture.zarr",
        program.plan,
        program.devices(),
        SessionSettings(rig=program.rig, backend="sim", seed=0),
    ) as store:
        create_s = time.perf_counter() - started
        if arguments.program == "run":
            timing = _run(program, store, arguments.leds)
        else:
            timing = _calibration(program, store, arguments.dark_share)
    dry_run = program.dry_run()
    results = {
        "machine": machine_description(),
        "variant": report.as_dict(),
        "load_average_before": [round(value, 2) for value in load_before],
        "load_average_after": [round(value, 2) for value in os.getloadavg()],
        "program": program.name,
        "material": arguments.material if arguments.program == "run" else None,
        "led_renders": arguments.led_renders,
        "frame_size": dry_run["frame_size"],
        "spp": program.rig.spp,
        "plan_steps": len(program.plan),
        "renders": dry_run["renders"],
        "store_creation_s": round(create_s, 2),
        **timing,
        "rig_estimate_h": round(dry_run["estimated_duration_h"], 2),
        "peak_rss_mib": peak_rss_mib(),
    }
    print(json.dumps(results, indent=2))


if __name__ == "__main__":
    main()
