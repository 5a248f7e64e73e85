"""Twin cameras fitted to EMVA 1288 measurements against those measurements, over several noise
seeds, and the time of the fit and of one repetition. Prints JSON.

The measurements: the shipped Basler CCD set (real, the official reference set 001 cropped to
128 x 128 px), and the two written by ``scripts/emva1288_reference_sets.py`` from known
parameters in the shape of the official sets 002 (8 bit, exposure-0 steps, quantization-limited
dark frames) and 003 (12 bit, one exposure time, a simulated camera that is not the twin's
model). Each is fitted as ``spectwin camera fit`` does; the fitted camera repeats it as
``spectwin camera CAMERA --emva`` does. For every figure: the real value (the emva1288 analysis
of the measurement), the twin's value for each seed (the same analysis of the fitted camera's
repetition), and the largest difference.

Run: .venv/bin/python -m benchmarks.emva_twin [--seeds N]
"""

from __future__ import annotations

import argparse
import json
import tempfile
import time
from pathlib import Path
from typing import Any

import numpy as np

from benchmarks.common import load_script, machine_description, peak_rss_mib
from recon.emva.analysis import analyse_measurement
from recon.emva.fit import fit_sensor
from recon.measured_data import data_path
from twin.rigs.fitted_camera import write_fitted_camera
from twin.studies.emva_twin import DEFAULT_DESCRIPTOR, run_emva_comparison


def _measurements(folder: Path) -> dict[str, tuple[Path, str]]:
    """Each measurement's descriptor and the serial of its fitted camera (the shipped Basler
    camera's for set 001: the same camera, the same fixed patterns)."""
    sets = load_script("emva1288_reference_sets")
    return {
        "set 001: Basler CCD, 12 bit (real)": (data_path(DEFAULT_DESCRIPTOR), "BASLER-EMVA-001"),
        "set 002's plan: twin 8-bit CMOS": (sets.write_cmos8(folder / "cmos8").path, "CMOS8-FIT"),
        "set 003's simulated camera, 12 bit": (
            sets.write_heidelberg(folder / "heidelberg").path,
            "HEIDELBERG-FIT",
        ),
    }


def _figures(runs: list[dict[str, Any]]) -> dict[str, Any]:
    figures = {}
    for key, row in runs[0]["figures"].items():
        twins = np.array([run["figures"][key]["twin"] for run in runs])
        differences = np.array([run["figures"][key]["difference_percent"] for run in runs])
        figures[key] = {
            "real": row["real"],
            "twin_per_seed": twins.tolist(),
            "twin_mean": float(np.nanmean(twins)) if np.isfinite(twins).any() else None,
            "difference_of_mean_percent": float(100 * (np.nanmean(twins) / row["real"] - 1))
            if np.isfinite(twins).any() and row["real"]
            else None,
            "largest_difference_percent": float(np.nanmax(np.abs(differences)))
            if np.isfinite(differences).any()
            else None,
        }
    return figures


def _round_trips(descriptor: Path, serial: str, folder: Path, seeds: range) -> dict[str, Any]:
    started = time.perf_counter()
    fitted = fit_sensor(analyse_measurement(descriptor), wavelength_nm=550.0)
    fit_s = time.perf_counter() - started
    camera = folder / "fitted.yaml"
    write_fitted_camera(fitted, camera, name=serial, serial=serial, pixel_pitch_um=7.4)
    runs, run_s = [], []
    for seed in seeds:
        started = time.perf_counter()
        runs.append(
            run_emva_comparison(camera, folder / str(seed), descriptor=descriptor, seed=seed)
        )
        run_s.append(time.perf_counter() - started)
    return {
        "fit_s": fit_s,
        "fitted": fitted.parameters(),
        "comparison_s": {"best": min(run_s), "worst": max(run_s)},
        "dsnu_detection_limit_e": runs[0]["dsnu_detection_limit_e"],
        "figures": _figures(runs),
    }


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--seeds", type=int, default=8)
    seeds = range(parser.parse_args().seeds)
    with tempfile.TemporaryDirectory() as folder:
        measurements = _measurements(Path(folder))
        results = {}
        for index, (name, (descriptor, serial)) in enumerate(measurements.items()):
            work = Path(folder) / f"twin_{index}"
            work.mkdir()
            results[name] = _round_trips(descriptor, serial, work, seeds)
    print(
        json.dumps(
            {
                "machine": machine_description(),
                "seeds": list(seeds),
                "measurements": results,
                "peak_rss_mib": peak_rss_mib(),
            },
            indent=2,
            default=float,
        )
    )


if __name__ == "__main__":
    main()
