"""Write EMVA 1288 measurements shaped like the official reference sets whose images the repository
does not hold, from known parameters, with spectwin's own writer (recon.emva.descriptor).

The EMVA1288/datasets repository holds three reference sets; spectwin ships the first (Basler
CCD, 12 bit, ``recon/data/real/emva1288_basler_ccd12``). Of the other two only what their
descriptors say is used here:

- ``ReferenceSet_002_CMOS_08Bit`` (STEMMER IMAGING, CC BY-SA 3.0): its descriptor is shipped in
  ``tests/data/emva1288_set002`` (not its images): an 8-bit CMOS, 100 temporal steps starting
  at exposure time 0 (``b 000.00 000.35``), 100 frames per spatial step. :func:`write_cmos8`
  repeats that plan, every step and frame, with a twin 8-bit camera whose dark frames are limited
  by quantization (read noise 0.2 DN), at a smaller frame size;
- ``ReferenceSet_003_Simulation_12Bit`` (B. Jaehne, HCI Heidelberg): a simulated camera whose
  recipe the descriptor's header gives. :func:`write_heidelberg` draws it again with that recipe
  (12 bit, K = 0.1 DN/e-, QE 0.5, dark noise 3 DN at 29.4 DN; a white and two sinusoidal DSNU
  patterns with outliers; 0.5 % white PRNU under an illumination falling off by 3 % towards the
  edges, with outliers; the cubic non-linearity ``y (1 - 0.02 (y / 4095)^3)``) and its plan: 50
  photon counts at one exposure time of 1 ms, one dark step, 100 frames per spatial step, image
  names with backslashes. It is not the twin's model: a camera a user might give.

The tests load this module (``tests/conftest.py``); ``benchmarks/emva_twin.py`` fits and repeats
its measurements. Run alone it writes both: ``python scripts/emva1288_reference_sets.py DIR``.
"""

from __future__ import annotations

import shutil
import sys
from dataclasses import replace
from pathlib import Path

import numpy as np

from recon.emva.descriptor import (
    DESCRIPTOR_NAME,
    EMVADescriptor,
    EMVAStep,
    read_descriptor,
    write_descriptor,
    write_frame,
)

SET_002 = (
    Path(__file__).resolve().parents[1] / "tests" / "data" / "emva1288_set002" / DESCRIPTOR_NAME
)

CMOS_8BIT = {
    "name": "twin 8-bit CMOS (reference set 002's plan)",
    "serial": "CMOS8-1288",
    "mosaic": "none",
    "width": 128,
    "height": 128,
    "pixel_pitch_um": 5.0,
    "bit_depth": 8,
    "sensor_temperature_c": 25.0,
    "exposure_range_s": [1e-8, 1e-3],
    "optics": {"f_number": 8.0},
    "quantum_efficiency": {
        "model": "ccd",
        "peak_qe": 0.5,
        "peak_nm": 550.0,
        "log_width_blue": 0.25,
        "log_width_red": 0.31,
    },
    "system_gain_dn_per_e": 0.033,
    "read_noise_dn": 0.2,  # below the quantizer's half DN: the dark frames are not dithered
    "full_well_e": 9000.0,  # beyond the ADC's top (248.7 DN = 7536 e-): the ADC clips first
    "adc_offset_dn": 6.3,
    "dark_current": {"e_per_s_at_reference": 10.0},
    "fixed_pattern": {"prnu_sigma": 0.015, "offset_sigma_dn": 0.25},
}
"""The twin camera that repeats reference set 002's plan (a ``scenes/cameras`` document)."""

HEIDELBERG = {
    "system_gain_dn_per_e": 0.1,
    "quantum_efficiency": 0.5,
    "dark_noise_dn": 3.0,
    "offset_dn": 29.4,
    "prnu": 0.005,
    "dsnu_white_dn": 1.5,
}
"""Reference set 003's simulated camera, as its descriptor's header gives it."""


def read_plan_002(folder: Path) -> EMVADescriptor:
    """Reference set 002's descriptor, read in ``folder`` with empty stand-ins for its images."""
    folder.mkdir(parents=True, exist_ok=True)
    descriptor = folder / DESCRIPTOR_NAME
    shutil.copyfile(SET_002, descriptor)
    for line in descriptor.read_text().splitlines():
        if line.startswith("i "):
            image = folder / line[2:]
            image.parent.mkdir(parents=True, exist_ok=True)
            image.touch()
    return read_descriptor(descriptor)


def write_cmos8(folder: Path, *, size: int = 128, seed: int = 1) -> EMVADescriptor:
    """Reference set 002's plan taken by the twin 8-bit camera :data:`CMOS_8BIT` at
    ``size`` x ``size`` px, written to ``folder``."""
    from twin.rigs.camera_config import CameraConfig
    from twin.sensor.emva_measurement import simulate_measurement

    plan = replace(read_plan_002(folder / "plan"), width=size, height=size)
    camera = CameraConfig.model_validate(CMOS_8BIT)
    return simulate_measurement(camera, plan, folder, wavelength_nm=550.0, seed=seed)


def _heidelberg_patterns(size: int, rng: np.random.Generator) -> tuple[np.ndarray, np.ndarray]:
    """The offsets (DN) and relative responses of set 003's camera: 100 outliers on 640 x 480
    px each, as many per pixel on ``size`` x ``size``."""
    camera = HEIDELBERG
    rows, cols = np.mgrid[0:size, 0:size].astype(float)
    outliers = max(1, round(100 * size * size / (640 * 480)))
    offsets = camera["offset_dn"] + camera["dsnu_white_dn"] * rng.standard_normal((size, size))
    offsets += 1.5 * np.sin(2 * np.pi * 0.04 * cols) + 1.5 * np.sin(2 * np.pi * 0.2 * rows)
    offsets.flat[rng.choice(size * size, outliers, replace=False)] += rng.uniform(0, 15, outliers)
    radius2 = ((rows - size / 2) ** 2 + (cols - size / 2) ** 2) / (2 * (size / 2) ** 2)
    response = (1 + camera["prnu"] * rng.standard_normal((size, size))) * (1 - 0.03 * radius2)
    weak = rng.choice(size * size, outliers, replace=False)
    response.flat[weak] *= rng.uniform(0.7, 1.0, outliers)
    return offsets, response


def _heidelberg_plan(folder: Path, size: int, spatial_frames: int) -> EMVADescriptor:
    """Set 003's plan: 50 photon counts at 1 ms, the spatial step at the 24th, one dark step."""

    def names(kind: str, count: int) -> tuple[str, ...]:
        return tuple(f"images\\{kind}_snap_{k:03d}.png" for k in range(1, count + 1))

    steps = [
        EMVAStep("bright", 1e6, round(1659.66 * i, 1), names(f"b_{i:03d}", 2)) for i in range(1, 51)
    ]
    steps.append(EMVAStep("bright", 1e6, round(1659.66 * 24, 1), names("b_s_024", spatial_frames)))
    steps.append(EMVAStep("dark", 1e6, 0.0, names("d_000", 2)))
    steps.append(EMVAStep("dark", 1e6, 0.0, names("d_s_000", spatial_frames)))
    return EMVADescriptor(12, size, size, tuple(steps), folder / DESCRIPTOR_NAME)


def write_heidelberg(
    folder: Path, *, size: int = 128, spatial_frames: int = 100, seed: int = 3
) -> EMVADescriptor:
    """Reference set 003's simulated camera and plan at ``size`` x ``size`` px, written to
    ``folder``: Poisson photo-electrons, normal dark noise, the non-linearity, rounding."""
    rng = np.random.default_rng(seed)
    camera = HEIDELBERG
    offsets, response = _heidelberg_patterns(size, rng)
    plan = _heidelberg_plan(folder, size, spatial_frames)
    top = 2**plan.bit_depth - 1
    for step in plan.steps:
        for name in step.images:
            electrons = rng.poisson(camera["quantum_efficiency"] * step.photons * response)
            value = offsets + camera["system_gain_dn_per_e"] * electrons
            value += camera["dark_noise_dn"] * rng.standard_normal(value.shape)
            value *= 1 - 0.02 * (value / top) ** 3
            write_frame(plan, name, np.clip(np.rint(value), 0, top))
    write_descriptor(
        plan, ["Reference set 003's simulated camera (scripts/emva1288_reference_sets.py)"]
    )
    return read_descriptor(plan.path)


if __name__ == "__main__":
    out = Path(sys.argv[1])
    for written in (write_cmos8(out / "cmos8"), write_heidelberg(out / "heidelberg")):
        print(written.path)
