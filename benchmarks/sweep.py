"""A design sweep's wall time and its time per design point, on a LocalCluster of ``--workers``
one-thread workers (1: in this process). Prints JSON.

Each design point is a virtual calibration session, measurement run, processing and held-out
evaluation (:mod:`twin.studies.sweep_gonio`); the sweep runs into a temporary folder unless
``--out`` names one. The load average before and after tells whether the machine was quiet.

    .venv/bin/python -m benchmarks.sweep gonio_lamp_filter_sampling --workers 2
    .venv/bin/python -m benchmarks.sweep gonio_lamp_filter_sampling --workers 16   # 16 cores
"""

from __future__ import annotations

import argparse
import json
import os
import tempfile
import time
from pathlib import Path

import numpy as np

from benchmarks.common import machine_description
from twin.devices.cluster import dask_client
from twin.kinds.registry import sweep_kind
from twin.studies.sweep_file import check_points, load_sweep, value_label
from twin.studies.sweep_run import run_sweep


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("sweep", help="A sweep file: a name in scenes/sweeps or a path.")
    parser.add_argument("--workers", type=int, default=2)
    parser.add_argument("--out", type=Path, default=None)
    arguments = parser.parse_args()
    sweep = load_sweep(arguments.sweep, sweep_kind)
    check, measure = sweep_kind(sweep.kind).check, sweep_kind(sweep.kind).measure
    check_points(sweep, check)
    load_before = os.getloadavg()
    with tempfile.TemporaryDirectory() as folder:
        out = arguments.out or Path(folder) / "sweep"
        started = time.perf_counter()
        with dask_client(arguments.workers) as client:
            outcome = run_sweep(sweep, out, measure, client=client)
        wall_s = time.perf_counter() - started
    rows = outcome.rows
    point_s = np.array([row["measures"]["point_s"] for row in rows])
    per_value = {
        name: {
            value_label(name, value): round(
                float(
                    np.mean([r["measures"]["point_s"] for r in rows if r["values"][name] == value])
                ),
                1,
            )
            for value in values
        }
        for name, values in sweep.parameters.items()
    }
    print(
        json.dumps(
            {
                "machine": machine_description(),
                "sweep": sweep.name,
                "points": len(rows),
                "workers": arguments.workers,
                "wall_s": round(wall_s, 1),
                "point_s": {
                    "mean": round(float(point_s.mean()), 1),
                    "min": round(float(point_s.min()), 1),
                    "max": round(float(point_s.max()), 1),
                    "sum": round(float(point_s.sum()), 1),
                },
                "mean_point_s_by_value": per_value,
                "front": outcome.summary["front"],
                "load_average_before_after": [
                    round(load_before[0], 2),
                    round(os.getloadavg()[0], 2),
                ],
            },
            indent=1,
        )
    )


if __name__ == "__main__":
    main()
