"""``spectwin validate`` on the three materials without chart fields (Lego, wallpaper, red
fabric), by the twin's own path and from files alone (``--photo``).

For each material the twin's true BTF (:func:`twin.render.truth_btf`, rings at 0, 30 and 60
degrees with 1, 4 and 4 directions: 9 x 9 pairs, 32 texels) is validated by the twin (its
photograph of the true material in its room, the room's map captured with a mirror sphere);
the twin writes the photograph, the map and the sample's corners as files, and the validation
is run again from those files: with the exposure given (1: the twin's photograph is in the
map's units) and fitted. Prints JSON: per material and path, the mean and median Delta E94 of
the spectral and the RGB rendering over the sample's interior, the fitted exposure, the times.

Run: .venv/bin/python -m benchmarks.validate_photo --out /tmp/validate_photo [--pixels 96]
[--spp 64] [--map-height 32]
"""

from __future__ import annotations

import argparse
import json
import time
from pathlib import Path

import numpy as np
from typer.testing import CliRunner

from benchmarks.common import machine_description
from recon.btf.store import write_btf
from recon.spectra import DEFAULT_GRID
from twin.cli.app import app
from twin.materials import load_material
from twin.render import truth_btf
from twin.rigs.hemisphere import sattler_directions

MATERIALS = ("lego", "wallpaper", "red_fabric")
KEYS = (
    "mean_delta_e94_spectral",
    "mean_delta_e94_rgb",
    "median_delta_e94_spectral",
    "median_delta_e94_rgb",
)


def _validate(*arguments: object) -> tuple[dict, float]:
    start = time.perf_counter()
    result = CliRunner().invoke(app, [str(a) for a in (*arguments, "--json")])
    if result.exit_code != 0:
        raise SystemExit(result.output)
    return json.loads(result.stdout), time.perf_counter() - start


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--out", type=Path, required=True)
    parser.add_argument("--pixels", type=int, default=96)
    parser.add_argument("--spp", type=int, default=64)
    parser.add_argument("--map-height", type=int, default=32)
    args = parser.parse_args()
    directions = sattler_directions(((0.0, 1), (30.0, 4), (60.0, 4)))
    lights, views = np.meshgrid(np.arange(len(directions)), np.arange(len(directions)))
    settings = ("--pixels", args.pixels, "--spp", args.spp)
    settings_used = {"pixels": args.pixels, "spp": args.spp, "map_height": args.map_height}
    report: dict = {"machine": machine_description(), "settings": settings_used | {"pairs": 81}}
    for material in MATERIALS:
        folder = args.out / material
        start = time.perf_counter()
        values = truth_btf(
            load_material(material),
            directions[lights.ravel()],
            directions[views.ravel()],
            texels=32,
            spp=16,
        )
        truth_s = time.perf_counter() - start
        store = folder / "truth.btf.zarr"
        write_btf(
            store,
            values.astype(np.float32),
            DEFAULT_GRID,
            light_dirs=directions[lights.ravel()],
            view_dirs=directions[views.ravel()],
            material=material,
        )
        twin, twin_s = _validate(
            "validate", store, "--out", folder / "twin", *settings, "--map-height", args.map_height
        )
        replay = twin["photo_inputs"]
        files = (
            "--photo",
            replay["photo"],
            "--environment",
            replay["environment"],
            "--sample-corners",
            replay["sample_corners"],
            "--fov-deg",
            replay["fov_deg"],
        )
        given, given_s = _validate(
            "validate", store, "--out", folder / "files", *files, *settings, "--exposure", 1
        )
        fitted, fitted_s = _validate(
            "validate", store, "--out", folder / "fitted", *files, *settings
        )
        report[material] = {
            "truth_btf_s": round(truth_s, 1),
            "twin": {k: round(twin["figure46"][k], 3) for k in KEYS} | {"s": round(twin_s, 1)},
            "files_exposure_1": {k: round(given["validation"][k], 3) for k in KEYS}
            | {"s": round(given_s, 1)},
            "files_exposure_fitted": {k: round(fitted["validation"][k], 3) for k in KEYS}
            | {"exposure": fitted["exposure"], "s": round(fitted_s, 1)},
            "figures": [str(folder / "twin" / "figure46.png"), fitted["figure"]],
        }
        print(json.dumps({material: report[material]}), flush=True)
    print(json.dumps(report, indent=2))


if __name__ == "__main__":
    main()
