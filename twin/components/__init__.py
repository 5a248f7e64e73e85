"""Spectra of the physical parts of the rigs: lamps, tunable filter, cameras, targets.

Each part cites the thesis section or figure it models; see the submodules.
"""

from twin.components.detectors import (
    RGB_CAMERA_RESPONSES,
    CCDQuantumEfficiency,
    rgb_camera_response,
)
from twin.components.lamps import (
    FINE_GRID,
    HMI_F575_LINES,
    EmissionLine,
    HMILamp,
    LightSource,
    PhosphorWhiteLED,
    QTHLamp,
    cie_illuminant,
    irradiance_at,
    lamp_model,
    planck_spectral_radiance,
)
from twin.components.lctf import VARISPEC_FWHM_NM, LiquidCrystalTunableFilter
from twin.components.targets import (
    COLORCHECKER_SOURCES,
    colorchecker_reflectances,
    esser_reflectances,
    zenith_white_reflectance,
)

__all__ = [
    "COLORCHECKER_SOURCES",
    "FINE_GRID",
    "HMI_F575_LINES",
    "RGB_CAMERA_RESPONSES",
    "VARISPEC_FWHM_NM",
    "CCDQuantumEfficiency",
    "EmissionLine",
    "HMILamp",
    "LightSource",
    "LiquidCrystalTunableFilter",
    "PhosphorWhiteLED",
    "QTHLamp",
    "cie_illuminant",
    "irradiance_at",
    "lamp_model",
    "colorchecker_reflectances",
    "esser_reflectances",
    "planck_spectral_radiance",
    "rgb_camera_response",
    "zenith_white_reflectance",
]
