"""How the calibrated capture-time figures move with the values fitted to the thesis. Prints JSON.

Two figures of the thesis were reproduced by fitting values it does not state:

- the gonioreflectometer's 134.9 h per material (4.1.1, ``twin.gonio.capture_time``): the fill
  fraction of the white standard and the K4's f-number (band exposures, 63.6 s per pair), the
  robot's joint speed and start-stop time (moves of about 5 s), the rail's speed and start-stop
  time (rail moves up to 20 s);
- the dome's longest band exposure, 5.48 s (``twin.dome.setup.THESIS_LONGEST_BAND_S``), derived
  from the thesis's +61 % for 10 RGB images (10.4); it sets the whole plan
  :math:`t_\\lambda = t_{base} / \\sqrt{E L}` and with it the schedules' exposure increases.

For every fitted value the script reports the figure at 0.9x, 1x and 1.1x the value (and at
the white fills 0.7 and 0.9) and the elasticity d ln(figure) / d ln(value) from the +-10 %
points: how far the reproduced figure is a product of the fit.

Run: .venv/bin/python -m benchmarks.capture_time_sensitivity [--dome-texels N]
"""

from __future__ import annotations

import argparse
import json
import math
import time

import numpy as np

from benchmarks.common import machine_description
from twin.dome.exposure_plan import band_schedules
from twin.dome.setup import THESIS_LONGEST_BAND_S, dome_setup
from twin.gonio.capture_time import band_exposures_s, move_seconds, order_pairs
from twin.rigs.gonio_kinematics import solve_pairs
from twin.rigs.rig_config import GonioConfig, load_rig
from twin.sensor.model import Sensor

THESIS_TOTAL_H = 134.9
FACTORS = (0.9, 1.0, 1.1)


def _with(config: GonioConfig, section: str, field: str, value: float) -> GonioConfig:
    part = getattr(config, section).model_copy(update={field: value})
    return config.model_copy(update={section: part})


class GonioModel:
    """The capture-time formula of ``twin.gonio.capture_time`` evaluated from its parts, so that
    a changed value recomputes only the part it enters (the kinematics are solved once)."""

    def __init__(self, config: GonioConfig):
        self.config = config
        solution = solve_pairs(config)
        order = order_pairs(solution)
        self.poses = [solution.poses[i] for i in order]

    def moves_s(self, config: GonioConfig) -> np.ndarray:
        return np.array(
            [
                move_seconds(a, b, config)
                for a, b in zip(self.poses[:-1], self.poses[1:], strict=True)
            ]
        )

    def exposures_s(self, config: GonioConfig, f_number: float | None = None) -> np.ndarray:
        sensor = None
        if f_number is not None:
            camera = Sensor(config.camera.definition).config
            optics = camera.optics.model_copy(update={"f_number": f_number})
            sensor = Sensor(camera.model_copy(update={"optics": optics}))
        return band_exposures_s(config, sensor=sensor)[1]

    def total_h(self, config: GonioConfig, *, f_number: float | None = None) -> dict[str, float]:
        exposures, moves = self.exposures_s(config, f_number), self.moves_s(config)
        timing = config.timing
        per_pair = exposures.sum() + exposures.size * timing.switch_and_download_s
        total_s = len(self.poses) * (per_pair + timing.settle_s) + moves.sum()
        return {
            "total_h": round(total_s / 3600, 2),
            "exposure_per_pair_s": round(float(exposures.sum()), 3),
            "mean_move_s": round(float(moves.mean()), 3),
            "max_move_s": round(float(moves.max()), 3),
        }


def _elasticity(low: float, high: float) -> float:
    return round(math.log(high / low) / math.log(1.1 / 0.9), 3)


def gonio_sensitivity() -> dict[str, object]:
    config = load_rig("gonio")
    model = GonioModel(config)
    f_number = Sensor(config.camera.definition).config.optics.f_number
    fitted = {
        "exposure.white_fill": (config.exposure.white_fill, "exposure", "white_fill"),
        "camera f_number (coolsnap_k4.yaml)": (f_number, None, None),
        "robot.joint_speed_deg_per_s": (
            config.robot.joint_speed_deg_per_s,
            "robot",
            "joint_speed_deg_per_s",
        ),
        "robot.start_stop_s": (config.robot.start_stop_s, "robot", "start_stop_s"),
        "rail.speed_deg_per_s": (config.rail.speed_deg_per_s, "rail", "speed_deg_per_s"),
        "rail.start_stop_s": (config.rail.start_stop_s, "rail", "start_stop_s"),
    }
    out: dict[str, object] = {"calibrated": model.total_h(config), "thesis_total_h": THESIS_TOTAL_H}
    for name, (value, section, field) in fitted.items():
        rows = {}
        for factor in FACTORS:
            if section is None:
                rows[f"x{factor:g}"] = model.total_h(config, f_number=value * factor)
            else:
                rows[f"x{factor:g}"] = model.total_h(_with(config, section, field, value * factor))
        out[name] = {
            "value": value,
            **rows,
            "elasticity_total": _elasticity(rows["x0.9"]["total_h"], rows["x1.1"]["total_h"]),
        }
    out["exposure.white_fill"]["at_0.7"] = model.total_h(
        _with(config, "exposure", "white_fill", 0.7)
    )
    out["exposure.white_fill"]["at_0.9"] = model.total_h(
        _with(config, "exposure", "white_fill", 0.9)
    )
    return out


def dome_sensitivity(texels: int) -> dict[str, object]:
    """The plan scales with the longest band (t_base is set by it), so one calibrated set-up and
    its exposures times each factor give every variant."""
    setup = dome_setup(texels)
    out: dict[str, object] = {
        "longest_band_s": THESIS_LONGEST_BAND_S,
        "thesis_increase_pct": {"8_images": 41.0, "10_images": 61.0},
    }
    rows = {}
    for factor in (0.8, *FACTORS, 1.2):
        plans = band_schedules(setup.exposures_s * factor)
        rows[f"x{factor:g}"] = {
            "band_exposures_sum_s": round(plans["band_exposures_sum_s"], 3),
            "increase_8_images_pct": round(plans["8_images"]["increase_pct"], 2),
            "fewest_images": plans["fewest_images"]["n_images"],
            "increase_10_images_pct": round(plans["10_images"]["increase_pct"], 2),
            "repeated_bands_nm": plans["10_images"]["repeated_bands_nm"],
        }
    out.update(rows)
    out["elasticity_10_image_total"] = _elasticity(
        1 + rows["x0.9"]["increase_10_images_pct"] / 100,
        1 + rows["x1.1"]["increase_10_images_pct"] / 100,
    )
    return out


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--dome-texels", type=int, default=16)
    arguments = parser.parse_args()
    started = time.perf_counter()
    results = {
        "machine": machine_description(),
        "gonio": gonio_sensitivity(),
        "dome": dome_sensitivity(arguments.dome_texels),
        "seconds": round(time.perf_counter() - started, 1),
    }
    print(json.dumps(results, indent=2))


if __name__ == "__main__":
    main()
