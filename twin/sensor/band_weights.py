"""The gonioreflectometer's band weighting: what one measured band averages (Eq. 3.3-3.6).

A band of a white-referenced BTF is the sample's reflectance averaged over wavelength with the
weights of the instrument: VariSpec transmission x the camera's electron response x the lamp's
mean spectrum (the rig's first lamp position). The twin compares measured bands with the truth
and with a 45/0 instrument through these weights.
"""

from __future__ import annotations

import numpy as np

from recon.spectra import SampledSpectra
from twin.components.lamps import FINE_GRID, lamp_model
from twin.components.lctf import LiquidCrystalTunableFilter
from twin.rigs.rig_config import GonioConfig
from twin.sensor.model import Sensor

__all__ = ["instrument_passbands"]


def instrument_passbands(config: GonioConfig) -> SampledSpectra:
    """The gonioreflectometer's band weighting: VariSpec transmission x the camera's electron
    response x the mean spectrum of the rig's (first) lamp, each band of unit area on
    ``FINE_GRID``. A measured band of a white-referenced BTF is the reflectance averaged with
    these weights (Eq. 3.3-3.6)."""
    lctf = LiquidCrystalTunableFilter.varispec(config.camera.filter)
    sensor = Sensor(config.camera.definition)
    responses = sensor.electron_responses(FINE_GRID, lctf.transmission(FINE_GRID))
    lamp = lamp_model(config.lamps[0].spectrum)
    mean_lamp = lamp.part_exposure_s(0.0, 1.0) @ lamp.spectral_parts(FINE_GRID).values
    weights = responses.values * mean_lamp
    weights /= np.trapezoid(weights, FINE_GRID.wavelengths_nm, axis=1)[:, None]
    return SampledSpectra(FINE_GRID, weights, responses.names)
