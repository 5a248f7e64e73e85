"""The llanos2019 bench's twin against its real capture: time of each phase and the prediction
errors, with the bench's own camera and filters and with each swapped for a wrong one (the
prediction must rest on them). Prints JSON.

Phases: reading the frames through the ingest mapping, rendering and fitting the twin, predicting
every frame (two simulations each at the camera's full size, reduced as the data set's copies).
The swaps use the noise-free prediction (the means do not need the noise).

Run: .venv/bin/python -m benchmarks.twin_vs_real [--spp N]
"""

from __future__ import annotations

import argparse
import json
import time

import numpy as np

from benchmarks.common import machine_description, peak_rss_mib
from twin.rigs.bench_config import load_bench
from twin.rigs.camera_config import RGBCSVQuantumEfficiencyConfig, load_camera_config
from twin.studies.bench_twin import bench_twin, read_real_capture
from twin.studies.twin_vs_real import compare_frames, mean_errors


def _errors(bench, twin, real, *, simulate: bool) -> dict:
    comparison = compare_frames(twin, real, simulate=simulate)
    colour = np.array(
        [index for index, name in enumerate(bench.chart.patches) if name not in bench.fit.patches]
    )
    errors = mean_errors(comparison, min_dn=bench.fit.min_dn, colour_rows=colour)
    return {
        name: {key: round(value, 4) for key, value in row.items()} for name, row in errors.items()
    }


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--spp", type=int, default=64)
    spp = parser.parse_args().spp
    bench = load_bench("llanos2019")
    times = {}
    started = time.perf_counter()
    real = read_real_capture(bench)
    times["read_s"] = time.perf_counter() - started
    started = time.perf_counter()
    twin = bench_twin(bench, real, spp=spp)
    times["render_and_fit_s"] = time.perf_counter() - started
    started = time.perf_counter()
    simulated = _errors(bench, twin, real, simulate=True)
    times["predict_frames_s"] = time.perf_counter() - started
    noise_free = _errors(bench, twin, real, simulate=False)
    nikon = load_camera_config(bench.camera).model_copy(
        update={
            "quantum_efficiency": RGBCSVQuantumEfficiencyConfig(
                model="rgb_csv", file="spectra/cameras_rawtoaces/Nikon_D850.csv", peak_qe=0.5
            )
        }
    )
    bands = sorted(bench.filters.columns)
    shifted = bench.model_copy(
        update={
            "filters": bench.filters.model_copy(
                update={
                    "columns": {
                        band: bench.filters.columns[bands[(index + 1) % len(bands)]]
                        for index, band in enumerate(bands)
                    }
                }
            )
        }
    )
    result = {
        "machine": machine_description(),
        "spp": spp,
        "frames": int(len(real.chart_frames)),
        "times": {key: round(value, 1) for key, value in times.items()},
        "peak_rss_mib": peak_rss_mib(),
        "lamp_position_m": np.round(twin.lamp.position_m, 3).tolist(),
        "errors_simulated_frames": simulated,
        "errors_noise_free": noise_free,
        "errors_with_nikon_d850_sensitivities": _errors(
            bench,
            bench_twin(bench, real, camera=nikon, dark=twin.dark, spp=spp),
            real,
            simulate=False,
        ),
        "errors_with_each_filter_taken_for_the_next": _errors(
            shifted, bench_twin(shifted, real, dark=twin.dark, spp=spp), real, simulate=False
        ),
    }
    print(json.dumps(result, indent=2))


if __name__ == "__main__":
    main()
