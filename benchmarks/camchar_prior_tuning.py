"""Tuning of the camera-response prior (recon.camera_prior in recon.camera_char). Prints JSON.

The prior has two settings: its principal components per channel and its weight lambda in the
extended estimator. This script chooses them on scenarios that the study
(``spectwin camchar-cameras``, seed 0 under D65) and the tests do not use: the same 240-field
chart and disturbances (``twin.studies.camchar_cameras``) under CIE D50 with seed 1000 and under
CIE D75 with seed 1001, all 51 cameras, each estimated with the prior learned from the other 50.
Objective: the lowest sum of the mean and the largest of the 102 errors (the worst channel's
RMSE in percent of the peak after one global scale): the goal bounds both, and a heavier prior
lowers the mean while it raises the error of the cameras least like the others.

Run: PYTHONPATH=. .venv/bin/python -m benchmarks.camchar_prior_tuning [--components 2 3 4 5]
[--weights 0.001 0.003 0.01 0.03 0.1]
"""

from __future__ import annotations

import argparse
import itertools
import json
import sys
import time

import numpy as np

from benchmarks.common import machine_description
from recon.camera_prior import PRIOR_COMPONENTS, PRIOR_WEIGHT
from twin.studies.camchar_cameras import characterize_cameras

SCENARIOS = (("D50", 1000), ("D75", 1001))


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--components", type=int, nargs="+", default=[2, 3, 4, 5])
    parser.add_argument("--weights", type=float, nargs="+", default=[1e-3, 3e-3, 1e-2, 3e-2, 1e-1])
    arguments = parser.parse_args()
    started = time.perf_counter()
    grid = []
    for components, weight in itertools.product(arguments.components, arguments.weights):
        errors, worst = [], []
        for light, seed in SCENARIOS:
            results = characterize_cameras(
                seed=seed,
                light=light,
                methods=("prior",),
                components=components,
                prior_weight=weight,
            )
            errors += [result.errors_pct["prior"] for result in results]
            worst.append(max(results, key=lambda result: result.errors_pct["prior"]).camera)
        values = np.array(errors)
        row = {
            "components": components,
            "prior_weight": weight,
            "mean_pct": round(float(values.mean()), 3),
            "p90_pct": round(float(np.percentile(values, 90)), 3),
            "max_pct": round(float(values.max()), 3),
            "worst_cameras": worst,
        }
        grid.append(row)
        print(json.dumps(row), file=sys.stderr, flush=True)
    best = min(grid, key=lambda row: row["mean_pct"] + row["max_pct"])
    results = {
        "machine": machine_description(),
        "scenarios": [{"light": light, "seed": seed} for light, seed in SCENARIOS],
        "objective": "lowest mean + largest error over 51 cameras x 2 scenarios",
        "grid": grid,
        "best": {"components": best["components"], "prior_weight": best["prior_weight"]},
        "shipped": {"components": PRIOR_COMPONENTS, "prior_weight": PRIOR_WEIGHT},
        "seconds": round(time.perf_counter() - started, 1),
    }
    print(json.dumps(results, indent=2))


if __name__ == "__main__":
    main()
