"""Timings of the sensor model on full 2048x2048 frames. Prints JSON.

Run: .venv/bin/python -m benchmarks.sensor
"""

from __future__ import annotations

import json
import time

import numpy as np

from benchmarks.common import machine_description, peak_rss_mib
from recon.spectra import DEFAULT_GRID
from twin.sensor.model import Sensor


def main() -> None:
    sensor = Sensor("coolsnap_k4")
    rng = np.random.default_rng(0)
    started = time.perf_counter()
    sensor.mean_dark_electrons(0.1)  # draws the fixed patterns once per camera
    fixed_pattern_s = time.perf_counter() - started
    # A smooth irradiance image on the sensor plane, W m^-2, up to about half of saturation.
    rows = np.linspace(0, 1, sensor.height, dtype=np.float32)[:, None]
    columns = np.linspace(0, 1, sensor.width, dtype=np.float32)[None, :]
    irradiance = 2e-3 * (0.2 + rows * columns)

    single = []
    for _ in range(3):
        started = time.perf_counter()
        electrons = sensor.electrons_from_monochromatic_irradiance(irradiance, 550.0, 0.1)
        sensor.capture(electrons, 0.1, rng)
        single.append(time.perf_counter() - started)

    started = time.perf_counter()
    for band_nm in DEFAULT_GRID.wavelengths_nm:
        electrons = sensor.electrons_from_monochromatic_irradiance(irradiance, band_nm, 0.1)
        sensor.capture(electrons, 0.1, rng)
    stack_s = time.perf_counter() - started

    print(
        json.dumps(
            {
                "machine": machine_description(),
                "camera": sensor.config.name,
                "frame_px": [sensor.height, sensor.width],
                "fixed_pattern_draw_s": round(fixed_pattern_s, 3),
                "frame_from_irradiance_s": {
                    "best": round(min(single), 3),
                    "worst": round(max(single), 3),
                },
                "stack_33_bands_s": round(stack_s, 2),
                "peak_rss_mib": peak_rss_mib(),
            },
            indent=2,
        )
    )


if __name__ == "__main__":
    main()
