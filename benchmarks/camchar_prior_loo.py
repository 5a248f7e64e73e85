"""Is the learned prior a safe default? Leave-one-out over the 51 measured cameras. Prints JSON.

``recon.camera_char.estimate_response`` and ``spectwin camchar`` use by default a prior learned
from the 51 measured cameras that ship with spectwin. Here each camera is left out of its own
prior in turn (learned from the other 50, ``twin.studies.camchar_cameras``) and estimated from
one simulated photograph with the prior and without it (the thesis's extended estimator), on
the same device RGB: the worst channel's RMSE after one global scale, % of the true peak.
Scenarios: the 240-field chart and the 24-patch ColorChecker Classic (the chart a user of
``spectwin camchar`` photographs), each under CIE D65, A (halogen) and FL11 (a three-band
fluorescent), with the study's specularity U[0, 0.1], shading in [0.8, 1.2] and noise of
0.5 % of the mean drawn from the seed. Per scenario: mean and largest error with and without
the prior, and the cameras the prior makes worse by more than ``--margin`` points.

Run: PYTHONPATH=. .venv/bin/python -m benchmarks.camchar_prior_loo [--charts 240 colorchecker]
     [--lights D65 A FL11] [--seeds 0] [--margin 0.5]
"""

from __future__ import annotations

import argparse
import json
import time

import numpy as np

from benchmarks.common import machine_description
from twin.studies.camchar_cameras import CHARTS, characterize_cameras


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--charts", nargs="+", default=list(CHARTS), choices=list(CHARTS))
    parser.add_argument("--lights", nargs="+", default=["D65", "A", "FL11"])
    parser.add_argument("--seeds", type=int, nargs="+", default=[0])
    parser.add_argument("--margin", type=float, default=0.5)
    arguments = parser.parse_args()
    started = time.perf_counter()
    scenarios = []
    worse_anywhere: dict[str, float] = {}
    for chart in arguments.charts:
        for light in arguments.lights:
            for seed in arguments.seeds:
                scenario_started = time.perf_counter()
                results = characterize_cameras(
                    seed=seed, light=light, chart=chart, methods=("prior", "extended")
                )
                prior = np.array([r.errors_pct["prior"] for r in results])
                plain = np.array([r.errors_pct["extended"] for r in results])
                change = prior - plain
                worse = {
                    r.camera: round(float(d), 2)
                    for r, d in zip(results, change, strict=True)
                    if d > arguments.margin
                }
                for camera, points in worse.items():
                    worse_anywhere[camera] = max(points, worse_anywhere.get(camera, points))
                scenarios.append(
                    {
                        "chart": chart,
                        "light": light,
                        "seed": seed,
                        "prior_mean_pct": round(float(prior.mean()), 2),
                        "prior_max_pct": round(float(prior.max()), 2),
                        "no_prior_mean_pct": round(float(plain.mean()), 2),
                        "no_prior_max_pct": round(float(plain.max()), 2),
                        "cameras_better_with_prior": int(np.sum(change < 0)),
                        "largest_gain_points": round(float(-change.min()), 2),
                        "largest_loss_points": round(float(change.max()), 2),
                        f"worse_by_over_{arguments.margin}_points": worse,
                        "per_camera_pct": {
                            r.camera: [round(p, 2), round(q, 2)]
                            for r, p, q in zip(results, prior, plain, strict=True)
                        },
                        "seconds": round(time.perf_counter() - scenario_started, 1),
                    }
                )
    print(
        json.dumps(
            {
                "machine": machine_description(),
                "cameras": 51,
                "margin_points": arguments.margin,
                "scenarios": scenarios,
                "worse_by_over_margin_anywhere": worse_anywhere,
                "seconds": round(time.perf_counter() - started, 1),
            },
            indent=2,
        )
    )


if __name__ == "__main__":
    main()
