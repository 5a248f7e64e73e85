"""Time of ``spectwin btf render`` (the BTF preview) for a gonioreflectometer-sampled, a
dome-sampled and an imported RGB BTF of the twin's Lego.

The stores are made here, not measured: the twin's true BTF of ``lego``
(:func:`twin.render.truth_btf`) at the gonioreflectometer's reduced directions (rings at 0, 30
and 60 degrees, 13 x 13 less the 13 pairs of light = view: 156 pairs) and at a reduced dome's
(12 of its LEDs, its 11 RGB cameras, 2 stage positions: 264 pairs, 24 lights x 22 views); the
RGB BTF is the gonio BTF as sRGB PNGs under D65, imported by ``spectwin btf import`` (Jakob 2019
upsampling). Each is rendered on a plane in the studio preset, the gonio BTF also on a sphere
in daylight. Prints JSON (wall time of each command, its render time, the line it printed).

Run: .venv/bin/python -m benchmarks.btf_preview --out /tmp/btf_preview [--pixels 256] [--spp 64]
"""

from __future__ import annotations

import argparse
import json
import time
from pathlib import Path

import numpy as np
from typer.testing import CliRunner

from benchmarks.common import machine_description
from recon.btf.rgb_import import DIRECTION_TABLE, RGB_COLUMNS
from recon.btf.store import write_btf
from recon.preview import spectral_to_xyz
from recon.spectra import DEFAULT_GRID
from twin.cli.app import app
from twin.materials import load_material
from twin.render import truth_btf
from twin.rigs.dome_geometry import dome_geometry, to_sample_frame
from twin.rigs.hemisphere import sattler_directions
from twin.rigs.rig_config import load_rig


def _gonio_pairs() -> tuple[np.ndarray, np.ndarray]:
    directions = sattler_directions(((0.0, 1), (30.0, 4), (60.0, 8)))
    lights = np.repeat(directions, len(directions), axis=0)
    views = np.tile(directions, (len(directions), 1))
    keep = np.einsum("ij,ij->i", lights, views) < 0.999
    return lights[keep], views[keep]


def _dome_pairs() -> tuple[np.ndarray, np.ndarray]:
    geometry = dome_geometry(load_rig("dome"))
    leds = geometry.led_directions[np.linspace(0, len(geometry.led_directions) - 1, 12).astype(int)]
    lights, views = [], []
    for stage_deg in (0.0, 90.0):
        for led in to_sample_frame(leds, stage_deg):
            for camera in to_sample_frame(geometry.rgb_camera_directions, stage_deg):
                lights.append(led)
                views.append(camera)
    return np.array(lights), np.array(views)


def _degrees(direction: np.ndarray) -> tuple[float, float]:
    theta = np.degrees(np.arccos(np.clip(direction[2], -1, 1)))
    return float(theta), float(np.degrees(np.arctan2(direction[1], direction[0])) % 360)


def _rgb_folder(folder: Path, lights, views, values) -> Path:
    import colour
    from skimage import io

    folder.mkdir()
    xyz = spectral_to_xyz(values * np.pi, DEFAULT_GRID)  # reflectance factor under equal energy
    white = spectral_to_xyz(np.ones(DEFAULT_GRID.size), DEFAULT_GRID)
    srgb = colour.XYZ_to_sRGB(xyz / white[1], illuminant=colour.XYZ_to_xy(white))
    rows = [",".join(RGB_COLUMNS)]
    for pair, image in enumerate(srgb):
        name = f"{pair:04d}.png"
        io.imsave(folder / name, (np.clip(image, 0, 1) * 255 + 0.5).astype(np.uint8))
        light, view = _degrees(lights[pair]), _degrees(views[pair])
        rows.append(f"{name},{light[0]:.6f},{light[1]:.6f},{view[0]:.6f},{view[1]:.6f}")
    (folder / DIRECTION_TABLE).write_text("\n".join(rows) + "\n")
    return folder


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__)
    parser.add_argument("--out", type=Path, required=True)
    parser.add_argument("--pixels", type=int, default=256)
    parser.add_argument("--spp", type=int, default=64)
    parser.add_argument("--texels", type=int, default=32)
    arguments = parser.parse_args()
    out: Path = arguments.out
    out.mkdir(parents=True, exist_ok=False)
    lego = load_material("lego")
    made = {}
    for name, (lights, views) in (("gonio", _gonio_pairs()), ("dome", _dome_pairs())):
        start = time.perf_counter()
        values = truth_btf(lego, lights, views, texels=arguments.texels, spp=16)
        write_btf(
            out / f"{name}.btf.zarr",
            values,
            DEFAULT_GRID,
            light_dirs=lights,
            view_dirs=views,
            material="lego",
        )
        made[name] = round(time.perf_counter() - start, 1)
        if name == "gonio":
            folder = _rgb_folder(out / "rgb_images", lights, views, values)
    runner = CliRunner()
    imported = runner.invoke(
        app, ["btf", "import", str(folder), "--out", str(out / "rgb.btf.zarr")]
    )
    assert imported.exit_code == 0, imported.output
    results = {}
    for store, options in (
        ("gonio", ("--preset", "studio", "--shape", "plane")),
        ("gonio", ("--preset", "daylight", "--shape", "sphere")),
        ("dome", ("--preset", "studio", "--shape", "plane")),
        ("rgb", ("--preset", "studio", "--shape", "plane")),
    ):
        target = out / f"{store}_{options[1]}_{options[3]}"
        start = time.perf_counter()
        result = runner.invoke(
            app,
            [
                "btf",
                "render",
                str(out / f"{store}.btf.zarr"),
                "--out",
                str(target),
                "--pixels",
                str(arguments.pixels),
                "--spp",
                str(arguments.spp),
                *options,
            ],
        )
        assert result.exit_code == 0, result.output
        summary = json.loads((target / "render.json").read_text())
        results[target.name] = {
            "wall_s": round(time.perf_counter() - start, 1),
            "render_s": summary["render_s"],
            "form": summary["form"],
            "measured_as": summary["measured_as"],
            "extrapolated": summary["extrapolated"],
            "png": str(target / "render.png"),
        }
    print(
        json.dumps(
            {
                "machine": machine_description(),
                "stores_made_s": made,
                "pixels": arguments.pixels,
                "spp": arguments.spp,
                "renders": results,
            },
            indent=2,
        )
    )


if __name__ == "__main__":
    main()
