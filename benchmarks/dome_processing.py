"""Time of the dome's processing at a reduced size, on this machine. Prints JSON.

Renders (Mitsuba, wall time recorded; ``spectwin capture --dry-run`` says how long the real rig
takes) a ``dome-calibration`` and a ``dome-run`` of ``--material`` at ``--stage-positions`` x
``--leds`` x ``--rgb-cameras``, ``--texels`` and ``--spp`` (default 2 x 24 x 3 at 64 texels and
the capture's spp), then times ``calibrate_dome`` and ``process_dome`` with numpy's BLAS held to
``--threads`` threads, and evaluates the BTF against the twin's truth (Eq. 6.8, Delta E94; not
timed).

Run: .venv/bin/python -m benchmarks.dome_processing [--out DIR] [--threads 2]
(``--out`` keeps the stores; an existing capture there is reused.)
"""

from __future__ import annotations

import argparse
import json
import shutil
import tempfile
from pathlib import Path

from threadpoolctl import threadpool_limits

from benchmarks.common import (
    add_dome_size_arguments,
    dome_size_settings,
    machine_description,
    peak_rss_mib,
    timed,
)
from recon.calibration.dome_capture import calibrate_dome
from recon.dome.processing import process_dome
from twin.dome.programs import DomeCaptureSize, dome_calibration_program, dome_run_program
from twin.validate.dome_evaluation import evaluate_dome


def main() -> None:
    parser = argparse.ArgumentParser()
    parser.add_argument("--material", default="lego")
    add_dome_size_arguments(parser)
    parser.add_argument("--dark-frames", type=int, default=200)
    parser.add_argument("--threads", type=int, default=2)
    parser.add_argument("--seed", type=int, default=2026)
    parser.add_argument("--out", type=Path, default=None, help="keep the stores here")
    arguments = parser.parse_args()
    root = arguments.out or Path(tempfile.mkdtemp(prefix="spectwin-dome-"))
    root.mkdir(parents=True, exist_ok=True)
    size = DomeCaptureSize(**dome_size_settings(arguments))
    stores = {
        "calibration": root / "cal.capture.zarr",
        "run": root / f"{arguments.material}.capture.zarr",
    }
    programs = {
        "calibration": dome_calibration_program(
            size=size, dark_frames=arguments.dark_frames, seed=arguments.seed
        ),
        "run": dome_run_program(arguments.material, size=size, seed=arguments.seed),
    }
    results: dict[str, object] = {
        "machine": machine_description(),
        "threads": arguments.threads,
        "size": dome_size_settings(arguments) | {"dark_frames": arguments.dark_frames},
        "material": arguments.material,
    }
    for name, program in programs.items():
        if not stores[name].exists():
            _, seconds = timed(lambda program=program, name=name: program.run(stores[name]))
            results[f"{name}_capture_render_s"] = seconds
        results[f"{name}_frames"] = len(program.plan)
    btf_path = root / f"{arguments.material}.btf.zarr"
    shutil.rmtree(btf_path, ignore_errors=True)
    with threadpool_limits(arguments.threads):
        calibration, results["calibrate_s"] = timed(lambda: calibrate_dome(stores["calibration"]))
        btf, results["process_s"] = timed(
            lambda: process_dome(stores["run"], calibration, btf_path)
        )
    results["btf_shape"] = list(btf.shape)
    results["process_s_per_pair"] = round(results["process_s"] / btf.n_pairs, 2)
    results["peak_rss_mib"] = peak_rss_mib()
    results["evaluation"] = evaluate_dome(btf_path).summary()
    print(json.dumps(results, indent=1))


if __name__ == "__main__":
    main()
