"""Spectral responses of the rigs' cameras: the cooled monochrome CCD and the RGB cameras.

References
----------
- The thesis, section 3.2.2 (Photometrics CoolSNAP K4: 2048x2048 CCD, 7.4 um pixels, cooled to
  -25 C) and Fig. 3.4b (blue-poor sensitivity of the spectral camera system), section 9.5 and
  Fig. 10.2b (effective responses of the RGB cameras).
- Kodak KAI-4021 Image Sensor device performance specification (the interline CCD of the K4
  class): monochrome quantum efficiency peaking near 0.55 around 490 nm. The curve here is a
  smooth two-sided log-normal model of that shape, not the datasheet's table.
- Darrodi, M. M., Finlayson, G., Goodman, T., & Mackiewicz, M. (2015). Reference data set for
  camera spectral sensitivity estimation. JOSA A, 32(3), 381-391. doi:10.1364/JOSAA.32.000381
  (the NPL-measured Nikon 5100 and Sigma SD Merrill, shipped by ``colour``).
- isetbio (MIT licence): Nikon D70, Nikon D100 and Aptina MT9M131 sensitivities in
  ``recon/data/spectra/sensors``.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

import colour
import numpy as np

from recon.errors import InputError
from recon.measured_data import read_spectra_csv
from recon.spectra import (
    OutOfRangePolicy,
    SampledSpectra,
    WavelengthGrid,
    from_colour,
    resample,
)

__all__ = ["RGB_CAMERA_RESPONSES", "CCDQuantumEfficiency", "rgb_camera_response"]


@dataclass(frozen=True)
class CCDQuantumEfficiency:
    """Quantum efficiency of a CoolSNAP K4-class interline CCD (electrons per photon).

    :math:`QE(\\lambda) = QE_{peak} \\exp(-\\tfrac12 (\\ln(\\lambda/\\lambda_{peak}) / s)^2)` with
    ``s`` = ``log_width_blue`` below the peak and ``log_width_red`` above it.
    """

    peak_qe: float = 0.55
    peak_nm: float = 490.0
    log_width_blue: float = 0.25
    log_width_red: float = 0.31

    def __post_init__(self) -> None:
        if not 0 < self.peak_qe <= 1:
            raise InputError(f"peak_qe: expected a value in (0, 1], got {self.peak_qe}")
        if not (self.peak_nm > 0 and self.log_width_blue > 0 and self.log_width_red > 0):
            raise InputError("peak_nm, log_width_blue, log_width_red: expected positive values")

    def __call__(self, grid: WavelengthGrid) -> SampledSpectra:
        log_ratio = np.log(grid.wavelengths_nm / self.peak_nm)
        width = np.where(log_ratio < 0, self.log_width_blue, self.log_width_red)
        return SampledSpectra(grid, self.peak_qe * np.exp(-0.5 * (log_ratio / width) ** 2))


def _colour_camera(name: str) -> Callable[[], SampledSpectra]:
    return lambda: from_colour(colour.MSDS_CAMERA_SENSITIVITIES[name])


def _isetbio_camera(file_name: str) -> Callable[[], SampledSpectra]:
    return lambda: read_spectra_csv(f"spectra/sensors/{file_name}")


RGB_CAMERA_RESPONSES: dict[str, Callable[[], SampledSpectra]] = {
    "Nikon 5100 (NPL)": _colour_camera("Nikon 5100 (NPL)"),
    "Sigma SDMerill (NPL)": _colour_camera("Sigma SDMerill (NPL)"),
    "Nikon D70": _isetbio_camera("nikon_d70_rgb.csv"),
    "Nikon D100": _isetbio_camera("nikon_d100_rgb.csv"),
    "Aptina MT9M131": _isetbio_camera("aptina_mt9m131_rgb.csv"),
}
"""Measured RGB camera sensitivities by name, each loaded on first use."""


def rgb_camera_response(
    name: str, grid: WavelengthGrid, *, out_of_range: OutOfRangePolicy = "error"
) -> SampledSpectra:
    """Effective RGB response :math:`R_{cam}` of a measured camera, values ``(3, K)``.

    Rows are named ``R``, ``G``, ``B`` and normalized so that the largest value is 1 (the
    measurements are relative).
    """
    if name not in RGB_CAMERA_RESPONSES:
        raise InputError(f"camera: expected one of {sorted(RGB_CAMERA_RESPONSES)}, got {name!r}")
    measured = RGB_CAMERA_RESPONSES[name]()
    response = resample(measured, grid, method="pchip", out_of_range=out_of_range)
    return SampledSpectra(grid, response.values / measured.values.max(), ("R", "G", "B"))
