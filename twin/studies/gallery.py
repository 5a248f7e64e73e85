"""One sensor-simulated frame of every ground-truth material in every rig, as PNGs.

Gonioreflectometer: the K4 frame of the 550 nm band for one direction pair (light 30 deg, view
15 deg from the normal), exposure from the rig's plan. Dome: the raw RGGB frame of the 45 deg
RGB camera with one LED on, demosaiced and white-balanced on the white paper of the holder for
display; and the spectral camera's 550 nm band frame after one stage step.
"""

from __future__ import annotations

import json
from pathlib import Path
from typing import Any

import numpy as np
from matplotlib.image import imsave

from recon.errors import InputError
from recon.radiometric.demosaic import demosaic
from twin.dome.render import dome_camera, dome_rates
from twin.gonio.capture_time import band_exposures_s
from twin.gonio.render import gonio_part_rates, simulate_band_frames
from twin.materials import available_materials, load_material
from twin.rigs.gonio_kinematics import solve_pairs
from twin.rigs.hemisphere import direction
from twin.rigs.rig_config import load_rig

__all__ = ["run_gallery"]

_BAND_550 = 15


def _exposure_for(rates: np.ndarray, saturation_e: float, limits: tuple[float, float]) -> float:
    """Exposure that brings the brightest 0.5 % of pixels to 70 % of saturation."""
    return float(np.clip(0.7 * saturation_e / np.percentile(rates, 99.5), *limits))


def run_gallery(
    out_dir: Path, *, pixels: int = 256, spp: int = 64, seed: int = 0
) -> dict[str, Any]:
    """Render and simulate the frames; write ``<rig>_<material>.png`` and ``gallery.json``."""
    out_dir.mkdir(parents=True, exist_ok=True)
    rng = np.random.default_rng(seed)
    gonio, dome = load_rig("gonio"), load_rig("dome")
    pose = solve_pairs(gonio, direction(30.0, 0.0)[None], direction(15.0, 180.0)[None]).poses[0]
    if pose is None:
        raise InputError("gonio: the robot reaches no pose near the gallery's pair")
    _, exposures = band_exposures_s(gonio)
    written = []
    for name in available_materials():
        material = load_material(name)
        rates = gonio_part_rates(gonio, pose, material, pixels=pixels, spp=spp, seed=seed)
        frames = simulate_band_frames(gonio, pose, rates, exposures, rng)
        imsave(out_dir / f"gonio_{name}.png", frames[_BAND_550], cmap="gray")

        view, sensor, _ = dome_camera(dome, 6, pixels)
        rgb_rates = dome_rates(
            dome, material, stage_deg=0.0, led=120, camera=6, pixels=pixels, spp=spp, seed=seed
        )
        window = sensor.__class__(sensor.config, roi=(pixels, pixels))
        exposure = _exposure_for(
            rgb_rates, window.saturation_capacity_e, window.config.exposure_range_s
        )
        raw = window.capture(rgb_rates * exposure, exposure, rng).astype(np.float64)
        rgb = demosaic(raw - window.config.adc_offset_dn)
        column, row = view.project(np.array([[0.0, -0.028, 0.0]])).astype(int)[0]
        paper = rgb[row - 1 : row + 2, column - 3 : column + 4].reshape(-1, 3)
        balanced = rgb / np.maximum(np.median(paper, axis=0), 1e-9)
        imsave(
            out_dir / f"dome_rgb_{name}.png",
            np.clip(balanced / np.percentile(balanced, 99), 0, 1) ** (1 / 2.2),
        )

        spectral_rates = dome_rates(
            dome,
            material,
            stage_deg=15.0,
            led=120,
            camera="spectral",
            pixels=pixels,
            spp=spp,
            seed=seed,
        )
        _, spectral_sensor, _ = dome_camera(dome, "spectral", pixels)
        window = spectral_sensor.__class__(spectral_sensor.config, roi=(pixels, pixels))
        band = spectral_rates[..., _BAND_550]
        exposure = _exposure_for(band, window.saturation_capacity_e, window.config.exposure_range_s)
        imsave(
            out_dir / f"dome_spectral_{name}.png",
            window.capture(band * exposure, exposure, rng),
            cmap="gray",
        )
        written += [f"gonio_{name}.png", f"dome_rgb_{name}.png", f"dome_spectral_{name}.png"]
    summary = {"pixels": pixels, "spp": spp, "seed": seed, "outputs": written}
    (out_dir / "gallery.json").write_text(json.dumps(summary, indent=2))
    return summary
