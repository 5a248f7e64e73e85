"""Timings of the rig renders. Prints JSON.

Run: .venv/bin/python -m benchmarks.rigs
"""

from __future__ import annotations

import json
import time

from benchmarks.common import machine_description, peak_rss_mib
from twin.dome.render import DOME_SPP, dome_rates
from twin.gonio.render import GONIO_SPP, GonioScene
from twin.materials import load_material
from twin.render.variant import activate
from twin.rigs.gonio_kinematics import solve_pairs
from twin.rigs.hemisphere import direction
from twin.rigs.rig_config import load_rig


def _best_of(function, repeats: int = 2) -> float:
    times = []
    for _ in range(repeats):
        started = time.perf_counter()
        function()
        times.append(time.perf_counter() - started)
    return min(times)


def main() -> None:
    report = activate()
    gonio, dome = load_rig("gonio"), load_rig("dome")
    pose = solve_pairs(gonio, direction(30.0, 0.0)[None], direction(15.0, 180.0)[None]).poses[0]
    results: dict[str, object] = {"machine": machine_description(), "variant": report.as_dict()}
    started = time.perf_counter()
    solve_pairs(gonio)
    results["gonio_kinematics_6561_pairs_s"] = round(time.perf_counter() - started, 2)
    for name in ("colorchecker16", "red_fabric"):
        material = load_material(name)
        started = time.perf_counter()
        scene = GonioScene(gonio, material)
        results[f"gonio_scene_{name}_s"] = round(time.perf_counter() - started, 2)
        for spp in (GONIO_SPP, 64, 256):
            results[f"gonio_pair_33_bands_256px_{name}_spp{spp}_s"] = round(
                _best_of(lambda s=spp, scene=scene: scene.part_rates(pose, pixels=256, spp=s)),
                3,
            )
        results[f"dome_rgb_frame_256px_{name}_spp{DOME_SPP}_s"] = round(
            _best_of(
                lambda m=material: dome_rates(dome, m, stage_deg=0, led=120, camera=6, pixels=256)
            ),
            2,
        )
    results["peak_rss_mib"] = peak_rss_mib()
    print(json.dumps(results, indent=2))


if __name__ == "__main__":
    main()
