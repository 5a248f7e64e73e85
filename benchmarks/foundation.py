"""Timings of the foundation: smoke render, spectral resampling, Delta E94. Prints JSON.

Run: .venv/bin/python -m benchmarks.foundation
"""

from __future__ import annotations

import json
import time

import numpy as np

from benchmarks.common import machine_description
from recon.metrics import delta_e94
from recon.spectra import DEFAULT_GRID, SampledSpectra, WavelengthGrid, resample
from twin.components.lamps import FINE_GRID, QTHLamp, irradiance_at
from twin.components.lctf import LiquidCrystalTunableFilter
from twin.components.targets import zenith_white_reflectance
from twin.render.flat_target import render_flat_target
from twin.render.variant import activate


def _timed(function, repeats: int = 3) -> tuple[float, float]:
    """First-call time (includes Dr.Jit kernel compilation) and best of the repeats."""
    started = time.perf_counter()
    function()
    first = time.perf_counter() - started
    times = []
    for _ in range(repeats):
        started = time.perf_counter()
        function()
        times.append(time.perf_counter() - started)
    return first, min(times)


def main() -> None:
    report = activate()
    bands = LiquidCrystalTunableFilter().transmission(FINE_GRID)
    irradiance = irradiance_at(QTHLamp().intensity(FINE_GRID), 2.0)
    white = zenith_white_reflectance(FINE_GRID)
    results: dict[str, object] = {
        "machine": machine_description(),
        "variant": report.as_dict(),
    }
    for spp in (64, 256):
        first, best = _timed(
            lambda spp=spp: render_flat_target(
                white, irradiance, bands, pixels_per_patch=64, spp=spp
            )
        )
        results[f"render_64x64x33_spp{spp}_s"] = {"first": round(first, 3), "best": round(best, 3)}

    fine = WavelengthGrid.regular(380, 780, 1)
    cube = SampledSpectra(fine, np.random.default_rng(0).random((256, 256, fine.size)))
    for method in ("linear", "pchip", "box"):
        first, best = _timed(lambda method=method: resample(cube, DEFAULT_GRID, method=method), 2)
        results[f"resample_256x256_401_to_33_{method}_s"] = round(best, 3)

    rng = np.random.default_rng(0)
    truth = rng.uniform(0.05, 0.95, (250, 400, DEFAULT_GRID.size))
    estimate = truth + 0.02 * rng.standard_normal(truth.shape)
    _, best = _timed(lambda: delta_e94(estimate, truth, DEFAULT_GRID), 2)
    results["delta_e94_250x400x33_s"] = round(best, 3)
    print(json.dumps(results, indent=2))


if __name__ == "__main__":
    main()
