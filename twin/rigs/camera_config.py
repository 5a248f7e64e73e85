"""Camera definitions: the pydantic schema of ``scenes/cameras/*.yaml`` and its loader.

A camera file names the sensor (size, pixel pitch, bit depth, temperature), its optics (f-number,
transmission), its spectral response, and the EMVA 1288 parameters of its noise model (system
gain, read noise, full well, dark current and its temperature law, fixed-pattern noise, OECF),
and, for a camera fitted to a real measurement, that measurement. Unknown keys, missing keys
and out-of-range values are rejected with the offending field named.

References
----------
- EMVA Standard 1288, Release 4.0 Linear (2021): the linear camera model and its parameters.
- The thesis, section 3.2.2 (CoolSNAP K4), section 10.2.1 (SVS-Vistek 4022), section 10.3 (read
  noise of 3 DN, dark frames, OECF).
"""

from __future__ import annotations

from pathlib import Path
from typing import Annotated, Literal

from pydantic import Field, model_validator

from recon.errors import DamagedDataError
from recon.measured_data import data_path, read_spectra_csv
from recon.spectra import SampledSpectra, WavelengthGrid, resample
from twin.components.detectors import CCDQuantumEfficiency, rgb_camera_response
from twin.rigs.yaml_config import (
    NonNegative,
    Positive,
    StrictModel,
    read_yaml_mapping,
    resolve_scene_file,
    scene_folder,
    scene_names,
    validate_document,
)

__all__ = ["CAMERA_DIR", "CameraConfig", "available_cameras", "load_camera_config"]

CAMERA_DIR = scene_folder("cameras")

MAX_SIDE_PX = 2**16
"""The most pixels along a side of a sensor (the largest real sensors have about 15000)."""

MAX_PIXELS = 2**28
"""The most pixels of a sensor (268 MP, four times the largest real ones): one frame of float64
values takes 2 GiB, and the twin holds several per capture."""

MAX_SYSTEM_GAIN_DN_PER_E = 100.0
"""The largest system gain K in DN per electron: at K = 100 a 16-bit ADC already saturates at
655 electrons; real cameras have K between about 0.01 and 20 (EMVA 1288 data sheets)."""


class OpticsConfig(StrictModel):
    """Lens in front of the sensor: :math:`E = \\pi \\tau L / (4 N^2)` (distant object)."""

    f_number: Positive
    transmission: Annotated[float, Field(gt=0, le=1)] = 1.0


class CCDQuantumEfficiencyConfig(StrictModel):
    """Monochrome CCD: the two-sided log-normal of ``twin.components.CCDQuantumEfficiency``."""

    model: Literal["ccd"]
    peak_qe: Annotated[float, Field(gt=0, le=1)]
    peak_nm: Positive
    log_width_blue: Positive
    log_width_red: Positive

    def curve(self, grid: WavelengthGrid) -> SampledSpectra:
        """:math:`\\eta(\\lambda)` on ``grid``, values ``(1, K)`` (channel ``"Y"``)."""
        curve = CCDQuantumEfficiency(
            self.peak_qe, self.peak_nm, self.log_width_blue, self.log_width_red
        )(grid)
        return SampledSpectra(grid, curve.values[None, :], ("Y",))


class RGBQuantumEfficiencyConfig(StrictModel):
    """Colour sensor: a measured relative RGB response scaled to a peak quantum efficiency."""

    model: Literal["rgb_camera"]
    camera: str
    peak_qe: Annotated[float, Field(gt=0, le=1)]

    def curve(self, grid: WavelengthGrid) -> SampledSpectra:
        """:math:`\\eta(\\lambda)` on ``grid``, values ``(3, K)`` (R, G, B); 0 outside the data."""
        return rgb_camera_response(self.camera, grid, out_of_range="zero") * self.peak_qe


class RGBCSVQuantumEfficiencyConfig(StrictModel):
    """Colour sensor: a relative RGB response from a CSV file (``wavelength_nm,R,G,B``), scaled to
    a peak quantum efficiency.

    ``file``: a path inside spectwin's measured data (``recon/data``) or an absolute path.
    """

    model: Literal["rgb_csv"]
    file: str
    peak_qe: Annotated[float, Field(gt=0, le=1)]

    def curve(self, grid: WavelengthGrid) -> SampledSpectra:
        """:math:`\\eta(\\lambda)` on ``grid``, values ``(3, K)`` (R, G, B); 0 outside the file's
        range, the largest value ``peak_qe``."""
        measured = read_spectra_csv(self.file)
        if measured.names != ("R", "G", "B"):
            raise DamagedDataError(
                f"{self.file}: expected the columns R, G, B, got {measured.names}"
            )
        measured.require_non_negative(self.file)
        response = resample(measured, grid, method="linear", out_of_range="zero")
        return SampledSpectra(
            grid, response.values * (self.peak_qe / measured.values.max()), ("R", "G", "B")
        )


class DarkCurrentConfig(StrictModel):
    """Dark current :math:`D(T) = D_{ref} 2^{(T - T_{ref}) / T_d}` in electrons per second."""

    e_per_s_at_reference: NonNegative
    reference_temperature_c: float = 25.0
    doubling_temperature_c: Positive = 6.3


class FixedPatternConfig(StrictModel):
    """Fixed-pattern noise, drawn once per camera serial.

    ``dsnu_sigma``: log-normal spread of the per-pixel dark current; ``prnu_sigma``: relative
    spread of the per-pixel photo response; hot pixels have ``hot_pixel_factor`` times the dark
    current; ``transfer_dark_e``: dark charge picked up during readout, growing linearly along the
    CCD shift direction (rows) to this value at the last row (thesis Fig. 10.2d);
    ``offset_sigma_dn``: standard deviation of the per-pixel offset (DN), the DSNU at zero
    exposure time; ``defect_pixel_fraction`` of the pixels are defects with an extra offset of
    ``defect_offset_dn`` at every exposure (bright pixels that no dark current explains).
    """

    dsnu_sigma: NonNegative = 0.0
    prnu_sigma: NonNegative = 0.0
    hot_pixel_fraction: Annotated[float, Field(ge=0, lt=0.1)] = 0.0
    hot_pixel_factor: Annotated[float, Field(ge=1)] = 1.0
    transfer_dark_e: NonNegative = 0.0
    offset_sigma_dn: NonNegative = 0.0
    defect_pixel_fraction: Annotated[float, Field(ge=0, lt=0.01)] = 0.0
    defect_offset_dn: NonNegative = 0.0


class OECFConfig(StrictModel):
    """Opto-electronic conversion: ``linear``, or ``knee`` with
    :math:`g(u) = (1 + s) u / (1 + s u)` on the signal normalized to the ADC range."""

    model: Literal["linear", "knee"] = "linear"
    strength: NonNegative = 0.0

    @model_validator(mode="after")
    def _strength_only_for_knee(self) -> OECFConfig:
        if self.model == "linear" and self.strength != 0:
            raise ValueError("strength applies to the 'knee' model only")
        return self


class EMVAMeasurementConfig(StrictModel):
    """The EMVA 1288 measurement a camera was fitted to (``spectwin camera fit``).

    ``descriptor``: its descriptor file, a relative path inside spectwin's measured data
    (``recon/data``) or an absolute path; ``wavelength_nm``: the wavelength of its light, where
    the camera's quantum efficiency was measured.
    """

    descriptor: str
    wavelength_nm: Positive

    def descriptor_path(self) -> Path:
        """The descriptor file (which may no longer exist where the fit found it)."""
        path = Path(self.descriptor)
        return path if path.is_absolute() else data_path(path)


class CameraConfig(StrictModel):
    """One camera of a rig (see the module docstring)."""

    name: str
    serial: str
    mosaic: Literal["none", "RGGB", "GBRG"]
    width: Annotated[int, Field(gt=0, le=MAX_SIDE_PX)]
    height: Annotated[int, Field(gt=0, le=MAX_SIDE_PX)]
    pixel_pitch_um: Positive
    bit_depth: Annotated[int, Field(ge=8, le=16)]
    sensor_temperature_c: float
    exposure_range_s: tuple[Positive, Positive]
    optics: OpticsConfig
    quantum_efficiency: (
        CCDQuantumEfficiencyConfig | RGBQuantumEfficiencyConfig | RGBCSVQuantumEfficiencyConfig
    ) = Field(discriminator="model")
    system_gain_dn_per_e: Annotated[float, Field(gt=0, le=MAX_SYSTEM_GAIN_DN_PER_E)]
    read_noise_dn: NonNegative
    full_well_e: Positive
    adc_offset_dn: NonNegative
    dark_current: DarkCurrentConfig
    fixed_pattern: FixedPatternConfig = FixedPatternConfig()
    oecf: OECFConfig = OECFConfig()
    emva1288: EMVAMeasurementConfig | None = None

    @model_validator(mode="after")
    def _consistent(self) -> CameraConfig:
        if self.width * self.height > MAX_PIXELS:
            raise ValueError(
                f"width x height: {self.width} x {self.height} pixels; expected at most "
                f"{MAX_PIXELS} pixels (2^28: one float64 frame takes 2 GiB)"
            )
        low, high = self.exposure_range_s
        if low > high:  # equal: a camera measured at one exposure time (EMVA 1288 set 003)
            raise ValueError(f"exposure_range_s: expected [shortest, longest], got {low}, {high}")
        if self.adc_offset_dn >= 2**self.bit_depth - 1:
            raise ValueError("adc_offset_dn: expected an offset below the ADC's largest value")
        colour_sensor = self.quantum_efficiency.model in ("rgb_camera", "rgb_csv")
        if colour_sensor != (self.mosaic != "none"):
            raise ValueError(
                "mosaic: an rgb_camera or rgb_csv response needs a Bayer mosaic and vice versa"
            )
        return self


def available_cameras() -> list[str]:
    """Names of the camera files in ``scenes/cameras`` (without ``.yaml``)."""
    return scene_names(CAMERA_DIR)


def load_camera_config(name_or_path: str | Path) -> CameraConfig:
    """Load a camera by file name in ``scenes/cameras`` (e.g. ``"coolsnap_k4"``) or by path."""
    path = resolve_scene_file(name_or_path, CAMERA_DIR, "camera")
    return validate_document(CameraConfig, read_yaml_mapping(path), path)
