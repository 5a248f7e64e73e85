"""The shipped Basler CCD twin against its real EMVA 1288 measurement, over several noise seeds,
and the time of the fit and of one repetition. Prints JSON.

For every figure: the real value (the emva1288 analysis of the shipped 128 x 128 px crop), the
twin's value for each seed (the same analysis of the twin's repetition of the measurement with
``scenes/cameras/basler_ccd12.yaml``), and the largest difference.

Run: .venv/bin/python -m benchmarks.emva_twin [--seeds N]
"""

from __future__ import annotations

import argparse
import json
import tempfile
import time
from pathlib import Path

import numpy as np

from benchmarks.common import machine_description, peak_rss_mib
from recon.emva.analysis import analyse_measurement
from recon.emva.fit import fit_sensor
from recon.measured_data import data_path
from twin.studies.emva_twin import DEFAULT_DESCRIPTOR, run_emva_comparison


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--seeds", type=int, default=8)
    seeds = range(parser.parse_args().seeds)
    started = time.perf_counter()
    fitted = fit_sensor(analyse_measurement(data_path(DEFAULT_DESCRIPTOR)), wavelength_nm=550.0)
    fit_s = time.perf_counter() - started
    runs, run_s = [], []
    with tempfile.TemporaryDirectory() as folder:
        for seed in seeds:
            started = time.perf_counter()
            runs.append(run_emva_comparison("basler_ccd12", Path(folder) / str(seed), seed=seed))
            run_s.append(time.perf_counter() - started)
    figures = {}
    for key, row in runs[0]["figures"].items():
        twins = np.array([run["figures"][key]["twin"] for run in runs])
        differences = np.array([run["figures"][key]["difference_percent"] for run in runs])
        figures[key] = {
            "real": row["real"],
            "twin_per_seed": twins.tolist(),
            "twin_mean": float(np.nanmean(twins)),
            "largest_difference_percent": float(np.nanmax(np.abs(differences)))
            if np.isfinite(differences).any()
            else None,
        }
    print(
        json.dumps(
            {
                "machine": machine_description(),
                "seeds": list(seeds),
                "fit_s": fit_s,
                "fitted": fitted.parameters(),
                "comparison_s": {"best": min(run_s), "worst": max(run_s)},
                "dsnu_detection_limit_e": runs[0]["dsnu_detection_limit_e"],
                "figures": figures,
                "peak_rss_mib": peak_rss_mib(),
            },
            indent=2,
            default=float,
        )
    )


if __name__ == "__main__":
    main()
