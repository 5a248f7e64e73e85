"""Timings of camera characterization (recon.camera_char). Prints JSON.

Run: .venv/bin/python -m benchmarks.camchar
"""

from __future__ import annotations

import json
import time

import colour
import numpy as np

from benchmarks.common import machine_description
from recon.camera_char import estimate_response
from recon.spectra import DEFAULT_GRID, from_colour, resample
from twin.components.detectors import rgb_camera_response
from twin.components.targets import esser_reflectances


def main() -> None:
    wavelengths = DEFAULT_GRID.wavelengths_nm
    chart = esser_reflectances(DEFAULT_GRID).values
    positions = np.array([[j % 11, j // 11] for j in range(len(chart))], dtype=float)
    response = rgb_camera_response("Nikon D70", DEFAULT_GRID).values.T
    light = resample(
        from_colour(colour.SDS_ILLUMINANTS["D65"]), DEFAULT_GRID, method="pchip"
    ).values
    rng = np.random.default_rng(0)
    x, y = positions.T / positions.max()
    shading = 1 + 0.2 * np.sin(2 * x + 1) * np.cos(1.5 * y)
    rgb = shading[:, None] * (
        ((chart + rng.uniform(0, 0.1, len(chart))[:, None]) * light) @ response
    )
    results: dict[str, object] = {
        "machine": machine_description(),
        "fields": len(chart),
        "bands": 33,
    }
    for method in ("basic", "extended"):
        times = []
        for _ in range(3):
            started = time.perf_counter()
            estimate_response(
                rgb,
                chart,
                light,
                wavelengths,
                method=method,
                field_positions=positions,
                prior=None,  # the thesis's estimators, as timed in BENCHMARKS.md
            )
            times.append(time.perf_counter() - started)
        results[f"{method}_s"] = round(min(times), 3)
    print(json.dumps(results, indent=2))


if __name__ == "__main__":
    main()
