"""The EMVA 1288 measurement procedure run on a twin camera.

Given the plan of a measurement (a descriptor: bit depth, size, exposure times, photons per pixel
and the images of every step), :func:`simulate_measurement` takes the same frames with a twin
camera under uniform monochromatic light: :math:`\\mu_e = \\eta(\\lambda) \\mu_p` photo-electrons
per pixel for a bright step, the shutter closed for a dark one, each frame with fresh temporal
noise and the camera's fixed patterns. A step at exposure time 0 (the official reference set 002
has them) is taken at the camera's shortest exposure, with the plan's photons. It writes the
frames and a descriptor in the same format, so the ``emva1288`` package analyses the twin's
measurement exactly as it analyses the real one.

References
----------
- EMVA Standard 1288, Release 3.0 (2010): section 6 (measurement set-up: uniform illumination
  of the bare sensor with monochromatic light), Eq. (2) (photons per pixel).
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import replace
from pathlib import Path, PureWindowsPath

import numpy as np

from recon.emva.descriptor import (
    DESCRIPTOR_NAME,
    EMVADescriptor,
    write_descriptor,
    write_frame,
)
from recon.errors import InputError
from recon.spectra import WavelengthGrid
from twin.rigs.camera_config import CameraConfig
from twin.sensor.model import Sensor

__all__ = ["simulate_measurement"]


def _sensor_for(config: CameraConfig, plan: EMVADescriptor) -> Sensor:
    if config.mosaic != "none":
        raise InputError(
            f"{config.name}: a colour camera ({config.mosaic} mosaic); the EMVA 1288 simulation "
            "expects a monochrome camera"
        )
    if plan.height > config.height or plan.width > config.width:
        raise InputError(
            f"{plan.path}: {plan.width}x{plan.height} px frames; {config.name} has "
            f"{config.width}x{config.height} px: expected a measurement no larger than the sensor"
        )
    low, high = config.exposure_range_s
    shortest, longest = plan.exposure_range_s
    if shortest < low or longest > high:
        raise InputError(
            f"{plan.path}: exposure times {shortest:g} to {longest:g} s; {config.name} takes "
            f"{low:g} to {high:g} s: expected a measurement within the camera's range"
        )
    return Sensor(config, roi=(plan.height, plan.width))


def simulate_measurement(
    config: CameraConfig,
    plan: EMVADescriptor,
    out_dir: Path,
    *,
    wavelength_nm: float,
    seed: int,
    header: tuple[str, ...] = (),
    step: Callable[[int, int], None] | None = None,
) -> EMVADescriptor:
    """Take the frames of a measurement plan with a twin camera and write them as a data set.

    Parameters
    ----------
    config
        The twin camera (monochrome).
    plan
        The measurement to repeat: its exposure times, photons per pixel, image counts and
        names (e.g. a real measurement read by :func:`recon.emva.descriptor.read_descriptor`).
    out_dir
        Folder for the descriptor (``EMVA1288_Data.txt``) and the images, named as in the plan.
    wavelength_nm
        The light's wavelength: the camera's quantum efficiency there turns photons into
        photo-electrons.
    seed
        Seed of the temporal noise (the fixed patterns come from the camera's serial).
    header
        ``#`` lines at the top of the written descriptor.
    step
        Called after every frame with the frames done and their total (progress).

    Returns
    -------
    EMVADescriptor
        The written measurement, in the camera's bit depth.
    """
    sensor = _sensor_for(config, plan)
    grid = WavelengthGrid(np.array([wavelength_nm, wavelength_nm + 1.0]))
    eta = float(sensor.quantum_efficiency(grid).values[0, 0])
    steps = tuple(
        replace(s, images=tuple(PureWindowsPath(name).as_posix() for name in s.images))
        for s in plan.steps
    )
    written = EMVADescriptor(
        config.bit_depth, plan.width, plan.height, steps, out_dir / DESCRIPTOR_NAME, plan.version
    )
    rng = np.random.default_rng(seed)
    shape = (plan.height, plan.width)
    shortest_s = config.exposure_range_s[0]
    done = 0
    for measurement_step in written.steps:
        electrons = np.full(shape, eta * measurement_step.photons, np.float32)
        exposure_s = measurement_step.exposure_s or shortest_s  # 0 ns: the shortest it makes
        for name in measurement_step.images:
            frame = sensor.capture(electrons, exposure_s, rng)
            write_frame(written, name, frame)
            done += 1
            if step is not None:
                step(done, written.frame_count)
    write_descriptor(written, header)
    return written
