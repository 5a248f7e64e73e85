"""Camera characterization across the 51 measured cameras, leave one out. Prints JSON.

The experiment of ``spectwin camchar-cameras`` (``twin.studies.camchar_cameras``): one chart
photograph per camera (240 measured reflectances, CIE D65, specularity U[0, 0.1], shading in
[0.8, 1.2], noise 0.5 % of the mean), the extended estimator with the prior learned from the
other 50 cameras, without prior, and Jiang et al. 2013 (colour-science) with its basis from the
same 50. Per seed: each method's mean, median and largest error over the cameras (the worst
channel's RMSE after one global scale, percent of the peak), the hardest cameras and the
per-camera errors; over all seeds, the means.

Run: PYTHONPATH=. .venv/bin/python -m benchmarks.camchar_cameras [--seeds 0 1 2 3]
"""

from __future__ import annotations

import argparse
import json
import time

import numpy as np

from benchmarks.common import machine_description
from twin.studies.camchar_cameras import METHODS, characterize_cameras


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--seeds", type=int, nargs="+", default=[0])
    arguments = parser.parse_args()
    started = time.perf_counter()
    runs = {}
    for seed in arguments.seeds:
        seed_started = time.perf_counter()
        results = characterize_cameras(seed=seed)
        errors = {m: np.array([r.errors_pct[m] for r in results]) for m in METHODS}
        runs[seed] = {
            method: {
                "mean_pct": round(float(values.mean()), 2),
                "median_pct": round(float(np.median(values)), 2),
                "max_pct": round(float(values.max()), 2),
                "hardest": [results[i].camera for i in np.argsort(values)[::-1][:3]],
            }
            for method, values in errors.items()
        }
        runs[seed]["per_camera_pct"] = {
            r.camera: {m: round(r.errors_pct[m], 2) for m in METHODS} for r in results
        }
        runs[seed]["prior_energy_of_truth"] = {r.camera: round(r.prior_energy) for r in results}
        runs[seed]["seconds"] = round(time.perf_counter() - seed_started, 1)
    print(
        json.dumps(
            {
                "machine": machine_description(),
                "seeds": arguments.seeds,
                "mean_over_seeds": {
                    method: {
                        key: round(float(np.mean([runs[s][method][key] for s in runs])), 2)
                        for key in ("mean_pct", "max_pct")
                    }
                    for method in METHODS
                },
                "runs": runs,
                "seconds": round(time.perf_counter() - started, 1),
            },
            indent=2,
        )
    )


if __name__ == "__main__":
    main()
