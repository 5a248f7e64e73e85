"""Light sources of the rigs: HMI and QTH lamps of the gonioreflectometer, the dome's white LEDs.

All lamps return spectral radiant intensity in W sr^-1 nm^-1 (``intensity``) and its integral
over an exposure window in J sr^-1 nm^-1 (``exposure_integral``), sampled on a caller's grid.
Narrow emission lines are sampled point-wise: evaluate on a grid that resolves them (e.g.
``FINE_GRID``) and reduce with ``recon.spectra.resample(..., method="box")``.

References
----------
- The thesis, section 3.2.1 (Broncolor F575 HMI lamp, about 6000 K), section 3.2.2 and Fig. 3.4
  (HMI line spectrum with the 545.9 nm peak, 15 Hz oscillation of the lines only, QTH 1000 W lamp
  black-body-like at about 3000 K), Eq. 3.6 and Fig. 3.5c (long-term drift of the HMI lamp,
  tracked by the X-Rite i1 monitor), section 10.3 and Fig. 10.2a (white LEDs of the dome).
- Ohno, Y. (2005). Spectral design considerations for white LED color rendering. Optical
  Engineering, 44(11), 111302. doi:10.1117/1.2130694 (the LED emission shape, via ``colour``).
- CODATA 2018 values of h, c and k_B via ``scipy.constants`` (Planck's law).
"""

from __future__ import annotations

from abc import ABC, abstractmethod
from collections.abc import Callable
from dataclasses import dataclass
from typing import Protocol

import colour
import numpy as np
from scipy import constants

from recon.errors import InputError
from recon.spectra import SampledSpectra, WavelengthGrid, from_colour, resample

__all__ = [
    "FINE_GRID",
    "HMI_F575_LINES",
    "EmissionLine",
    "HMILamp",
    "LightSource",
    "PhosphorWhiteLED",
    "QTHLamp",
    "cie_illuminant",
    "irradiance_at",
    "lamp_model",
    "planck_spectral_radiance",
]

FINE_GRID = WavelengthGrid.regular(360.0, 830.0, 0.25)
"""Grid fine enough for 2 nm wide emission lines; spans Mitsuba's spectral range."""

_NORMALIZATION_RANGE_NM = (380.0, 780.0)


def planck_spectral_radiance(wavelengths_nm: np.ndarray, temperature_k: float) -> np.ndarray:
    """Black-body spectral radiance :math:`B_\\lambda(T)` in W m^-2 sr^-1 nm^-1 (Planck's law).

    Parameters
    ----------
    wavelengths_nm
        Wavelengths in nm.
    temperature_k
        Absolute temperature in K, positive.
    """
    if not temperature_k > 0:
        raise InputError(f"temperature_k: expected a positive temperature, got {temperature_k}")
    wavelength_m = np.asarray(wavelengths_nm, dtype=np.float64) * 1e-9
    h, c, k = constants.h, constants.c, constants.k
    per_metre = (
        2 * h * c**2 / wavelength_m**5 / np.expm1(h * c / (wavelength_m * k * temperature_k))
    )
    return per_metre * 1e-9


def _require_exposure(t0_s: float, exposure_s: float) -> None:
    if not np.isfinite(t0_s) or t0_s < 0:
        raise InputError(f"t0_s: expected a finite, non-negative start time, got {t0_s}")
    if not np.isfinite(exposure_s) or exposure_s <= 0:
        raise InputError(f"exposure_s: expected a positive exposure time, got {exposure_s}")


class LightSource(Protocol):
    """What the rigs need of a light source.

    A lamp's output is a sum of fixed spectral parts whose weights change in time
    (``spectral_parts`` and ``part_exposure_s``). Anything linear in the light, a render or
    a sensor's mean signal, can therefore be computed once per part and combined per frame:
    ``exposure_integral`` = sum over parts of ``part_exposure_s`` x ``spectral_parts``.
    """

    def intensity(self, grid: WavelengthGrid, t_s: float = 0.0) -> SampledSpectra:
        """Spectral radiant intensity at time ``t_s`` in W sr^-1 nm^-1."""

    def spectral_parts(self, grid: WavelengthGrid) -> SampledSpectra:
        """Time-averaged intensity of each part, values ``(n_parts, K)``, W sr^-1 nm^-1."""

    def part_exposure_s(self, t0_s: float, exposure_s: float) -> np.ndarray:
        """Effective seconds each part shines during ``[t0_s, t0_s + exposure_s]``."""

    def exposure_integral(
        self, grid: WavelengthGrid, t0_s: float, exposure_s: float
    ) -> SampledSpectra:
        """Integral of the intensity over ``[t0_s, t0_s + exposure_s]`` in J sr^-1 nm^-1."""


def _combine_parts(parts: SampledSpectra, weights_s: np.ndarray) -> SampledSpectra:
    return SampledSpectra(parts.grid, weights_s @ parts.values)


def _intensity_scale(
    relative_spectrum: Callable[[np.ndarray], np.ndarray], radiant_intensity_w_sr: float
) -> float:
    """Factor that makes ``relative_spectrum`` integrate to ``radiant_intensity_w_sr`` over
    380-780 nm."""
    if not radiant_intensity_w_sr > 0:
        raise InputError(
            f"radiant_intensity_w_sr: expected a positive intensity, got {radiant_intensity_w_sr}"
        )
    fine = FINE_GRID.wavelengths_nm
    inside = fine[(fine >= _NORMALIZATION_RANGE_NM[0]) & (fine <= _NORMALIZATION_RANGE_NM[1])]
    return radiant_intensity_w_sr / np.trapezoid(relative_spectrum(inside), inside)


class _SteadyLamp(ABC):
    """A lamp whose output does not change in time: the exposure integral is intensity x time."""

    radiant_intensity_w_sr: float

    @abstractmethod
    def relative_spectrum(self, wavelengths_nm: np.ndarray) -> np.ndarray:
        """Spectral shape in arbitrary units."""

    def intensity(self, grid: WavelengthGrid, t_s: float = 0.0) -> SampledSpectra:
        scale = _intensity_scale(self.relative_spectrum, self.radiant_intensity_w_sr)
        return SampledSpectra(grid, scale * self.relative_spectrum(grid.wavelengths_nm))

    def spectral_parts(self, grid: WavelengthGrid) -> SampledSpectra:
        intensity = self.intensity(grid)
        return SampledSpectra(grid, intensity.values[None, :], ("steady",))

    def part_exposure_s(self, t0_s: float, exposure_s: float) -> np.ndarray:
        _require_exposure(t0_s, exposure_s)
        return np.array([exposure_s])

    def exposure_integral(
        self, grid: WavelengthGrid, t0_s: float, exposure_s: float
    ) -> SampledSpectra:
        return _combine_parts(self.spectral_parts(grid), self.part_exposure_s(t0_s, exposure_s))


@dataclass(frozen=True)
class QTHLamp(_SteadyLamp):
    """Quartz tungsten halogen lamp (Newport 1000 W, thesis 3.2.2): a grey body, no flicker.

    Parameters
    ----------
    temperature_k
        Colour temperature, about 3000 K (Fig. 3.4d).
    radiant_intensity_w_sr
        Intensity integrated over 380-780 nm in W/sr.
    """

    temperature_k: float = 3000.0
    radiant_intensity_w_sr: float = 20.0

    def relative_spectrum(self, wavelengths_nm: np.ndarray) -> np.ndarray:
        """Planck's law at ``temperature_k`` (shape only; scaled by ``intensity``)."""
        return planck_spectral_radiance(wavelengths_nm, self.temperature_k)


@dataclass(frozen=True)
class EmissionLine:
    """A Gaussian emission line: centre, full width at half maximum, and peak height.

    ``peak`` is relative to the lamp's continuum at 560 nm.
    """

    centre_nm: float
    fwhm_nm: float
    peak: float

    def profile(self, wavelengths_nm: np.ndarray) -> np.ndarray:
        return self.peak * np.exp(
            -4 * np.log(2) * ((np.asarray(wavelengths_nm) - self.centre_nm) / self.fwhm_nm) ** 2
        )


HMI_F575_LINES = (
    EmissionLine(435.8, 2.0, 0.9),
    EmissionLine(545.9, 2.0, 2.0),
    EmissionLine(578.0, 3.0, 1.2),
)
"""The three oscillating peaks of the Broncolor F575 spectrum (thesis Fig. 3.4a, 3.4c): the
545.9 nm peak named in the thesis and the mercury lines near 436 and 578 nm. Heights and widths
are a model at the resolution of the thesis's Ocean Optics USB4000, not a measurement."""


@dataclass(frozen=True)
class HMILamp:
    """Hydrargyrum medium-arc iodide lamp (Broncolor F575, thesis 3.2.1-3.2.2).

    The spectrum is a thermal continuum plus narrow emission lines. The lines oscillate at
    ``flicker_hz`` (15 Hz, Fig. 3.4c/e) with relative amplitude ``flicker_depth``; the continuum
    does not. A slow drift scales the whole output as
    :math:`d(t) = 1 + a (1 - e^{-t/\\tau})` (Fig. 3.5c), the long-term change that the thesis
    tracks with the i1 monitor and removes with :math:`F_{i,long}` (Eq. 3.6).

    Parameters
    ----------
    radiant_intensity_w_sr
        Time-averaged intensity integrated over 380-780 nm in W/sr at drift 1.
    continuum_temperature_k
        Colour temperature of the continuum.
    lines
        The emission lines.
    flicker_hz, flicker_depth, flicker_phase_rad
        Line modulation :math:`1 + m \\sin(2 \\pi f t + \\varphi)`.
    drift_fraction, drift_time_constant_s
        :math:`a` and :math:`\\tau` of the drift.
    """

    radiant_intensity_w_sr: float = 40.0
    continuum_temperature_k: float = 6000.0
    lines: tuple[EmissionLine, ...] = HMI_F575_LINES
    flicker_hz: float = 15.0
    flicker_depth: float = 0.5
    flicker_phase_rad: float = 0.0
    drift_fraction: float = -0.02
    drift_time_constant_s: float = 3 * 3600.0

    def __post_init__(self) -> None:
        if not 0 <= self.flicker_depth <= 1:
            raise InputError(
                f"flicker_depth: expected a modulation depth in [0, 1], got {self.flicker_depth}"
            )
        if not self.flicker_hz > 0 or not self.drift_time_constant_s > 0:
            raise InputError("flicker_hz and drift_time_constant_s: expected positive values")

    def _relative_parts(self, wavelengths_nm: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        continuum = planck_spectral_radiance(wavelengths_nm, self.continuum_temperature_k)
        continuum = continuum / planck_spectral_radiance(
            np.array(560.0), self.continuum_temperature_k
        )
        lines = sum(line.profile(wavelengths_nm) for line in self.lines)
        return continuum, lines + np.zeros_like(continuum)

    def continuum_and_lines(self, wavelengths_nm: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Time-averaged continuum and line parts in W sr^-1 nm^-1 at drift 1."""
        scale = _intensity_scale(
            lambda wavelengths: np.add(*self._relative_parts(wavelengths)),
            self.radiant_intensity_w_sr,
        )
        continuum, lines = self._relative_parts(np.asarray(wavelengths_nm, dtype=np.float64))
        return scale * continuum, scale * lines

    def drift(self, t_s: float) -> float:
        """Long-term output factor :math:`d(t)` (Fig. 3.5c)."""
        return 1.0 + self.drift_fraction * (1.0 - np.exp(-t_s / self.drift_time_constant_s))

    def intensity(self, grid: WavelengthGrid, t_s: float = 0.0) -> SampledSpectra:
        """Instantaneous intensity at ``t_s`` seconds after the lamp was switched on."""
        continuum, lines = self.continuum_and_lines(grid.wavelengths_nm)
        phase = 2 * np.pi * self.flicker_hz * t_s + self.flicker_phase_rad
        modulation = 1.0 + self.flicker_depth * np.sin(phase)
        return SampledSpectra(grid, self.drift(t_s) * (continuum + modulation * lines))

    def spectral_parts(self, grid: WavelengthGrid) -> SampledSpectra:
        """The steady continuum and the flickering lines, values ``(2, K)``."""
        continuum, lines = self.continuum_and_lines(grid.wavelengths_nm)
        return SampledSpectra(grid, np.stack([continuum, lines]), ("continuum", "lines"))

    def part_exposure_s(self, t0_s: float, exposure_s: float) -> np.ndarray:
        """Effective seconds of continuum and lines in ``[t0_s, t0_s + exposure_s]``.

        The line modulation is integrated exactly, so any window whose length is a multiple of
        ``1 / flicker_hz`` (66.7 ms for 15 Hz, thesis 3.2.2) sees the same energy whatever its
        phase. The drift is evaluated at the middle of the window (it changes over hours).
        """
        _require_exposure(t0_s, exposure_s)
        omega = 2 * np.pi * self.flicker_hz
        start = omega * t0_s + self.flicker_phase_rad
        stop = start + omega * exposure_s
        line_time = exposure_s + self.flicker_depth * (np.cos(start) - np.cos(stop)) / omega
        return self.drift(t0_s + exposure_s / 2) * np.array([exposure_s, line_time])

    def exposure_integral(
        self, grid: WavelengthGrid, t0_s: float, exposure_s: float
    ) -> SampledSpectra:
        """Intensity integrated over ``[t0_s, t0_s + exposure_s]`` in J sr^-1 nm^-1."""
        return _combine_parts(self.spectral_parts(grid), self.part_exposure_s(t0_s, exposure_s))


@dataclass(frozen=True)
class PhosphorWhiteLED(_SteadyLamp):
    """Phosphor-converted white LED of the dome (Barthelme 2.5 W, thesis 10.2.1, Fig. 10.2a).

    A blue InGaN emission plus the broad emission of its phosphor, each with the LED shape of
    Ohno (2005) as implemented by ``colour.sd_single_led``.

    Parameters
    ----------
    blue_peak_nm, blue_fwhm_nm
        Blue die emission.
    phosphor_peak_nm, phosphor_fwhm_nm
        Phosphor emission.
    phosphor_to_blue
        Peak height of the phosphor relative to the blue peak.
    radiant_intensity_w_sr
        On-axis intensity integrated over 380-780 nm in W/sr.
    """

    blue_peak_nm: float = 450.0
    blue_fwhm_nm: float = 22.0
    phosphor_peak_nm: float = 560.0
    phosphor_fwhm_nm: float = 125.0
    phosphor_to_blue: float = 0.7
    radiant_intensity_w_sr: float = 0.25

    def relative_spectrum(self, wavelengths_nm: np.ndarray) -> np.ndarray:
        shape = colour.SpectralShape(FINE_GRID.start_nm, FINE_GRID.stop_nm, 0.25)
        blue = colour.colorimetry.sd_single_led_Ohno2005(
            self.blue_peak_nm, self.blue_fwhm_nm, shape
        )
        phosphor = colour.colorimetry.sd_single_led_Ohno2005(
            self.phosphor_peak_nm, self.phosphor_fwhm_nm, shape
        )
        emission = from_colour(blue) * (1 / blue.values.max())
        emission = SampledSpectra(
            emission.grid,
            emission.values + self.phosphor_to_blue * phosphor.values / phosphor.values.max(),
        )
        target = WavelengthGrid(wavelengths_nm)
        return resample(emission, target, out_of_range="zero").values


def cie_illuminant(name: str, grid: WavelengthGrid) -> SampledSpectra:
    """Relative spectral power of a CIE illuminant from ``colour.SDS_ILLUMINANTS`` (e.g. "D65")."""
    if name not in colour.SDS_ILLUMINANTS:
        raise InputError(
            f"illuminant: expected a name of colour.SDS_ILLUMINANTS "
            f"({', '.join(sorted(colour.SDS_ILLUMINANTS))}), got {name!r}"
        )
    return resample(from_colour(colour.SDS_ILLUMINANTS[name]), grid, method="pchip")


def lamp_model(spectrum: str) -> LightSource:
    """The gonioreflectometer lamp a rig file names: ``"hmi"`` (Broncolor F575, flickering
    lines) or ``"qth"`` (the 1000 W tungsten-halogen lamp), thesis 3.2.2."""
    models = {"hmi": HMILamp, "qth": QTHLamp}
    if spectrum not in models:
        raise InputError(f"lamp spectrum: expected 'hmi' or 'qth', got {spectrum!r}")
    return models[spectrum]()


def irradiance_at(intensity: SampledSpectra, distance_m: float) -> SampledSpectra:
    """Irradiance on a surface facing a point-like lamp: :math:`E = I / d^2` (W m^-2 nm^-1)."""
    if not distance_m > 0:
        raise InputError(f"distance_m: expected a positive distance, got {distance_m}")
    return intensity.require_non_negative("lamp intensity") * (1.0 / distance_m**2)
