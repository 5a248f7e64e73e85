"""Registration of gonio runs at small ``--pixels``: the marks' predicted width
(``twin.gonio.mark_width``) against the pairs that processing leaves unregistered.

Captures a gonio calibration session and calibrates it (once, into ``--root``), then for each
pixel count captures a measurement run of 12 direction pairs (lights at 30 and 45 degrees, views
from 0 to 60 degrees at several azimuths; the rig's default samples per pixel), processes it at
16 texels and prints, per pixel count, each pair's predicted narrowest print side, the pairs
predicted unlikely to register and those that may not, and the pairs left unregistered. Prints
JSON lines.

Run: .venv/bin/python -m benchmarks.registration_pixels [--root DIR] [PIXELS ...]
"""

from __future__ import annotations

import argparse
import json
import shutil
import subprocess
import sys
import time
from pathlib import Path

import numpy as np

from recon.btf.processing import process_gonio
from recon.btf.store import BTFStore
from recon.calibration.gonio import GonioCalibration
from twin.gonio.capture import GonioPairs, gonio_measurement_program
from twin.gonio.mark_width import mark_widths_px
from twin.rigs.hemisphere import direction
from twin.rigs.rig_config import load_rig

VIEWS_THETA = [0, 15, 30, 40, 45, 50, 55, 60, 60, 45, 30, 60]
VIEWS_PHI = [0, 90, 45, 135, 0, 180, 90, 0, 135, 270, 180, 225]


def _calibration(root: Path) -> GonioCalibration:
    """The calibration of a twin calibration session, captured and calibrated once."""
    if not (root / "cal.json").exists():
        spectwin = [sys.executable, "-m", "twin.cli.app"]
        capture = root / "cal.capture.zarr"
        subprocess.run([*spectwin, "capture", "gonio-calibration", str(capture)], check=True)
        subprocess.run(
            [*spectwin, "calibrate", str(capture), "--out", str(root / "cal.json")], check=True
        )
    return GonioCalibration.load(root / "cal.json")


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__)
    parser.add_argument("pixels", type=int, nargs="*", default=[64, 96, 128, 160, 192, 215, 256])
    parser.add_argument("--root", type=Path, default=Path("out/registration_pixels"))
    arguments = parser.parse_args()
    arguments.root.mkdir(parents=True, exist_ok=True)
    calibration = _calibration(arguments.root)
    config = load_rig("gonio")
    lights = direction(np.array([30.0] * 6 + [45.0] * 6), np.array([0.0, 60.0] * 6))
    views = direction(np.array(VIEWS_THETA, float), np.array(VIEWS_PHI, float))
    pairs = GonioPairs(config, lights, views)
    for pixels in arguments.pixels:
        start = time.perf_counter()
        program = gonio_measurement_program(
            calibration.planned_exposure_s, pairs=pairs, pixels=pixels, seed=1
        )
        outlook = program.registration_outlook()
        assert outlook is not None
        store = arguments.root / f"run{pixels}.capture.zarr"
        btf = arguments.root / f"run{pixels}.btf.zarr"
        for path in (store, btf):
            shutil.rmtree(path, ignore_errors=True)
        program.run(store)
        process_gonio(store, calibration, btf, texels=16)
        unregistered = list(BTFStore.open(btf).metadata.unregistered_pairs or ())
        widths = mark_widths_px(config, program.poses.values(), pixels)
        print(
            json.dumps(
                {
                    "pixels": pixels,
                    "widths_px": np.round(widths, 2).tolist(),
                    "unlikely": list(outlook.unlikely),
                    "maybe": list(outlook.maybe),
                    "unregistered": unregistered,
                    "seconds": round(time.perf_counter() - start, 1),
                }
            ),
            flush=True,
        )


if __name__ == "__main__":
    main()
