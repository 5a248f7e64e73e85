"""Spectral reflectances of the ground-truth materials, designed on a 5 nm grid.

Colours come from the ColorChecker (``colour``); metamers are designed for the dome's RGB camera
under the dome's white LEDs (``recon.metamers``). Renders use the same spectra on ``FINE_GRID``.
"""

from __future__ import annotations

import numpy as np

from recon.metamers import design_metamer
from recon.spectra import SampledSpectra, WavelengthGrid, resample
from twin.components import FINE_GRID, PhosphorWhiteLED, colorchecker_reflectances
from twin.sensor.model import Sensor

__all__ = ["MATERIAL_GRID", "chart_colour", "dome_camera_and_light", "metamer_of", "on_fine_grid"]

MATERIAL_GRID = WavelengthGrid.regular(380.0, 780.0, 5.0)
"""Grid the material spectra are designed on; they are linear between its samples."""


def chart_colour(name: str, scale: float = 1.0) -> SampledSpectra:
    """A ColorChecker patch reflectance (``ColorChecker N Ohta``), optionally scaled."""
    return colorchecker_reflectances(MATERIAL_GRID).row(name) * scale


def dome_camera_and_light() -> tuple[SampledSpectra, SampledSpectra]:
    """The dome RGB camera's quantum efficiency (R, G, B) and the dome LED spectrum."""
    response = Sensor("svs_vistek_4022").quantum_efficiency(MATERIAL_GRID)
    return response, PhosphorWhiteLED().intensity(MATERIAL_GRID)


def metamer_of(reflectance: SampledSpectra, seed: int, percent: float = 20.0) -> SampledSpectra:
    """A smooth metamer of ``reflectance`` for the dome camera under the dome LEDs."""
    response, light = dome_camera_and_light()
    return design_metamer(
        reflectance,
        response,
        light,
        np.random.default_rng(seed),
        relative_difference_percent=percent,
    )


def on_fine_grid(reflectance: SampledSpectra) -> SampledSpectra:
    """The design spectrum on the render grid (linear in between, held constant outside)."""
    return resample(reflectance, FINE_GRID, out_of_range="clamp")
