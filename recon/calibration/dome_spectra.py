"""The dome's spectra measured at calibration (thesis 10.3), from a ``dome-calibration`` store.

A real dome knows neither its LEDs' spectrum nor its RGB cameras' spectral response; the thesis
measures both:

1. **The LED spectrum** (:func:`measured_led_spectrum`): the spectrometer's readings of the white
   standard (the store's ``lamp_monitor`` of the ``white`` frames) under the calibration LED,
   averaged and divided by the white standard's certified reflectance; the same under every other
   LED of the calibration gives the LED-to-LED spread of the spectrum's shape.
2. **Each RGB camera's spectral response** (:func:`measured_camera_response`): the camera's
   photographs of the charts under the calibration LED (the colour checker of its response
   series, ``oecf``, and a second chart, ``chart``: 24 fields leave a response's shape loosely
   constrained) merged to linear RGB per Bayer quad, each field's mean over the quads wholly
   inside it (its corners projected by the calibrated camera), divided by the LED's irradiance
   fall-off over the chart, and the chapter 9 extended estimator
   (:func:`recon.camera_char.estimate_response`, with the prior learned from measured cameras)
   given the fields' certified reflectances and the measured LED spectrum. A camera that resolves
   fewer than :data:`MIN_FIELDS` fields is left out.

What a lab takes from certificates rather than frames: the white standard's and the charts'
reflectances (recorded with the store's rig), and the spectral camera's band passbands (the
filter's nominal 10 nm cells: measuring their shape needs a monochromator; 10.3 calibrates only
their sensitivity, against the spectrometer's reading of the white standard).

References
----------
- The thesis, section 10.3 (the LED spectrum measured with an Ocean Optics USB4000, the RGB
  cameras by the method of chapter 9) and Eq. 9.6-9.14.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np

from hwbridge.schema import DomeChart, DomeRigAttrs, Spectrum
from hwbridge.store import CaptureStore
from recon.calibration.dome_geometric import CameraGeometry
from recon.calibration.dome_lighting import led_irradiance
from recon.camera_char import (
    CharacterizationResult,
    MeasuredPrior,
    estimate_response,
    fit_residuals,
)
from recon.camera_prior import ResponsePrior
from recon.errors import InputError
from recon.registration.corners import texture_transform
from recon.spectra import SampledSpectra, WavelengthGrid, resample

__all__ = [
    "FIELD_FRACTION",
    "CameraResponse",
    "MIN_FIELDS",
    "MeasuredLedSpectrum",
    "RESIDUAL_FLOOR_PCT",
    "band_response",
    "chart_field_rgb",
    "combined_response",
    "measured_camera_response",
    "measured_led_spectrum",
    "response_weights",
    "rig_spectrum",
    "square_region",
]

FIELD_FRACTION = 0.9
"""Fraction of a chart field's square (its side) whose pixels give the field's mean RGB: a pixel
counts where it lies wholly inside, so that no neighbour's light mixes in, with a margin of a
tenth of the side for registration error (the cameras' reprojection error is a fifth of a pixel)."""

MIN_FIELDS = 12
"""Fewest resolved chart fields a camera's response is estimated from."""

RESIDUAL_FLOOR_PCT = 0.5
"""Smallest chart fit residual (%) :func:`combined_response` weighs a camera by."""


def rig_spectrum(spectrum: Spectrum, grid: WavelengthGrid) -> np.ndarray:
    """A spectrum the capture stores with its rig (e.g. a certificate's ``white_reflectance``),
    linearly interpolated to ``grid`` (rows first), zero outside its range."""
    source = WavelengthGrid(np.asarray(spectrum.wavelengths_nm, np.float64))
    values = SampledSpectra(source, np.asarray(spectrum.values, np.float64))
    return resample(values, grid, out_of_range="zero").values


def band_response(response: np.ndarray, led: np.ndarray, white: np.ndarray) -> np.ndarray:
    """:math:`R_{cam}` ``(K, 3)`` (Eq. 10.1) in the spectral camera's bands: the camera's
    response ``(K, 3)`` times the LED's spectrum ``(K,)``, scaled so that the white standard
    ``(K,)`` reads one in every channel.

    Examples
    --------
    >>> band_response(np.ones((30, 3)), np.ones(30), np.ones(30)).sum(axis=0).round(12).tolist()
    [1.0, 1.0, 1.0]
    """
    shape = np.asarray(response, np.float64) * np.asarray(led, np.float64)[:, None]
    return shape / (np.asarray(white, np.float64) @ shape)


@dataclass(frozen=True)
class MeasuredLedSpectrum:
    """The LEDs' relative spectrum measured on the white standard (module docstring).

    Attributes
    ----------
    wavelengths_nm
        ``(n,)`` the spectrometer's wavelengths.
    values
        ``(n,)`` the calibration LED's spectrum, peak one.
    uncertainty
        ``(n,)`` the standard error of :attr:`values` from the readings' scatter.
    readings
        Readings averaged for the calibration LED.
    spread_pct
        Per other LED photographed on the white standard: the RMS difference of its spectrum's
        shape (peak one) from the calibration LED's, in % of the peak.
    """

    wavelengths_nm: np.ndarray
    values: np.ndarray
    uncertainty: np.ndarray
    readings: int
    spread_pct: dict[int, float]

    def on(self, grid: WavelengthGrid) -> np.ndarray:
        """The spectrum averaged over each cell of ``grid`` (``resample(..., method="box")``)."""
        spectrum = SampledSpectra(WavelengthGrid(self.wavelengths_nm), self.values)
        return resample(spectrum, grid, method="box", out_of_range="zero").values

    def summary(self) -> dict[str, object]:
        return {
            "wavelengths_nm": self.wavelengths_nm.tolist(),
            "values": self.values.tolist(),
            "uncertainty": self.uncertainty.tolist(),
            "readings": self.readings,
            "spread_pct": {str(led): value for led, value in self.spread_pct.items()},
        }

    @classmethod
    def from_summary(cls, summary: dict[str, Any]) -> MeasuredLedSpectrum:
        return cls(
            np.asarray(summary["wavelengths_nm"], np.float64),
            np.asarray(summary["values"], np.float64),
            np.asarray(summary["uncertainty"], np.float64),
            int(summary["readings"]),
            {int(led): float(value) for led, value in summary["spread_pct"].items()},
        )


def _white_readings(store: CaptureStore, cameras: list[str]) -> dict[int, np.ndarray]:
    """Per LED, the spectrometer's readings ``(n, samples)`` of the white standard under it alone
    (the ``white`` frames of ``cameras``)."""
    readings: dict[int, list[np.ndarray]] = {}
    for camera in cameras:
        index = store.index(camera, ("kind", "light_id"))
        white = np.flatnonzero(index["kind"] == "white")
        if white.size == 0:
            continue
        spectra = store.index(camera, ("lamp_monitor",))["lamp_monitor"][white]
        for light, spectrum in zip(index["light_id"][white], spectra, strict=True):
            if light >= 0 and np.all(np.isfinite(spectrum)):
                readings.setdefault(int(light), []).append(spectrum)
    return {light: np.array(values, np.float64) for light, values in readings.items()}


def measured_led_spectrum(store: CaptureStore, rig: DomeRigAttrs) -> MeasuredLedSpectrum:
    """The LEDs' spectrum from the spectrometer's readings of the white standard in a
    ``dome-calibration`` store (module docstring, step 1)."""
    if rig.spectrometer_wavelengths_nm is None:
        raise InputError(
            f"{store.path}: the calibration capture has no spectrometer readings of the white "
            "standard; capture the calibration with a spectrometer on the holder"
        )
    grid = WavelengthGrid(np.asarray(rig.spectrometer_wavelengths_nm, np.float64))
    white = rig_spectrum(rig.white_reflectance, grid)
    if np.any(white <= 0):
        raise InputError(
            f"{store.path}: the white standard's certificate does not cover the spectrometer's "
            f"{grid.start_nm:g}-{grid.stop_nm:g} nm"
        )
    readings = _white_readings(store, list(rig.geometry.cameras))
    if rig.calibration_led not in readings:
        raise InputError(
            f"{store.path}: no spectrometer reading of the white standard under the calibration "
            f"LED {rig.calibration_led}"
        )

    def shape(values: np.ndarray) -> tuple[np.ndarray, np.ndarray, float]:
        spectrum = values.mean(axis=0) / white
        scatter = values.std(axis=0, ddof=1) if len(values) > 1 else np.zeros(grid.size)
        peak = float(spectrum.max())
        if not peak > 0:
            raise InputError(f"{store.path}: the spectrometer read no light on the white standard")
        return spectrum / peak, scatter / white / peak / np.sqrt(len(values)), peak

    values, uncertainty, _ = shape(readings[rig.calibration_led])
    spread = {
        light: float(100 * np.sqrt(np.mean((shape(other)[0] - values) ** 2)))
        for light, other in readings.items()
        if light != rig.calibration_led
    }
    return MeasuredLedSpectrum(
        grid.wavelengths_nm.copy(),
        values,
        uncertainty,
        len(readings[rig.calibration_led]),
        spread,
    )


def square_region(corners_xy: np.ndarray, shape: tuple[int, int]) -> np.ndarray:
    """The pixels of an image of ``shape`` whose centres lie inside the quadrilateral of
    ``corners_xy`` ``(4, 2)`` (pixel edges at integers, in the texture's corner order)."""
    rows, columns = np.indices(shape)
    centres = np.stack([columns.ravel() + 0.5, rows.ravel() + 0.5], axis=1)
    uv = texture_transform(np.asarray(corners_xy, np.float64))(centres)
    return np.all((uv > 0) & (uv < 1), axis=1).reshape(shape)


def chart_field_rgb(
    image: np.ndarray,
    geometry: CameraGeometry,
    chart: DomeChart,
    led_position_m: np.ndarray,
    fraction: float = FIELD_FRACTION,
    *,
    binning: int = 1,
    centre_pixels: bool = False,
) -> np.ndarray:
    """Mean linear RGB ``(J, 3)`` of every chart field in ``image`` ``(H, W, 3)`` (stage position
    0; each of its pixels ``binning`` x ``binning`` of the camera's, e.g. 2 for Bayer quads):
    the mean of the pixels that lie wholly inside the central ``fraction`` of the field's
    square, divided by the LED's relative irradiance at the field's centre
    (:func:`recon.calibration.dome_lighting.led_irradiance`); NaN for a field no pixel lies
    inside (too small in the camera's view: not resolved). With ``centre_pixels`` each field's
    RGB is the pixel at its centre instead, resolved or not."""
    centres = np.asarray(chart.field_centres_m, np.float64)
    height, width = image.shape[:2]
    half = fraction * chart.field_half_m
    square = np.array([[-half, half, 0], [half, half, 0], [half, -half, 0], [-half, -half, 0]])
    means = np.full((len(centres), image.shape[-1]), np.nan)
    for field, centre in enumerate(centres):
        # the field's corners with pixel edges at integers, in units of the image's pixels
        corners = (geometry.project(centre + square) + 0.5) / binning
        outside = (corners < 0) | (corners > [width, height])
        if outside.any():
            raise InputError(
                f"chart field {field + 1}: outside the camera's {width} x {height} px image"
            )
        (left, top), (right, bottom) = np.floor(corners.min(0)), np.ceil(corners.max(0))
        rows, columns = np.mgrid[top : bottom + 1, left : right + 1]
        grid = np.stack([columns.ravel(), rows.ravel()], axis=1)
        if centre_pixels:
            column, row = np.floor(corners.mean(axis=0)).astype(int)
            means[field] = image[row, column]
            continue
        uv = texture_transform(corners)(grid).reshape(*rows.shape, 2)
        within = np.all((uv >= 0) & (uv <= 1), axis=-1)
        inside = within[:-1, :-1] & within[1:, :-1] & within[:-1, 1:] & within[1:, 1:]
        if inside.any():
            block = image[int(top) : int(bottom), int(left) : int(right)]
            means[field] = block[inside].mean(axis=0)
    irradiance = led_irradiance(centres, led_position_m)
    return means / (irradiance / irradiance.mean())[:, None]


@dataclass(frozen=True)
class CameraResponse:
    """An RGB camera's spectral response measured from its chart photograph.

    Attributes
    ----------
    values
        ``(K, 3)`` the response in the spectral camera's bands, peak one per channel.
    fit_residual_pct
        RMS of what the fitted model leaves of the fields' RGB (Eq. 9.7), in % of their mean.
    centre_pixels
        The fields were not resolved by any camera (a capture of few texels): each field's RGB is
        the pixel at its centre, its neighbours' light mixed in.
    """

    values: np.ndarray
    fit_residual_pct: float
    centre_pixels: bool = False


def measured_camera_response(
    field_rgb: Sequence[np.ndarray],
    charts: Sequence[DomeChart],
    led: MeasuredLedSpectrum,
    grid: WavelengthGrid,
    *,
    prior: ResponsePrior | MeasuredPrior | None = "measured",
    centre_pixels: bool = False,
) -> CameraResponse:
    """An RGB camera's response on ``grid`` from the fields' RGB ``(J_c, 3)`` of each of its
    ``charts`` (:func:`chart_field_rgb`), all under the same light, by the extended estimator
    (Eq. 9.6-9.14) with ``prior`` (module docstring, step 2). The charts' fields are one set,
    each chart's its own shading neighbourhood (Eq. 9.9); ``centre_pixels`` says how the fields'
    RGB was taken (:func:`chart_field_rgb`)."""
    if len(field_rgb) != len(charts) or not charts:
        raise InputError(f"charts: {len(charts)} described, {len(field_rgb)} photographed")
    reflectances, positions, first_row = [], [], 0.0
    for rgb, chart in zip(field_rgb, charts, strict=True):
        reflectance = SampledSpectra(
            WavelengthGrid(np.asarray(chart.reflectance.wavelengths_nm, np.float64)),
            np.atleast_2d(np.asarray(chart.reflectance.values, np.float64)),
        )
        fields = resample(reflectance, grid, method="box", out_of_range="clamp").values
        if fields.shape[0] != len(rgb):
            raise InputError(
                f"chart {chart.name}: {fields.shape[0]} certified fields, {len(rgb)} photographed"
            )
        index = np.arange(fields.shape[0])
        rows = index // chart.columns + first_row
        positions.append(np.column_stack([index % chart.columns, rows]).astype(float))
        reflectances.append(np.clip(fields, 0.0, 1.0))
        first_row = rows.max() + 2  # apart, so that no shading neighbourhood spans two charts
    all_rgb = np.concatenate(field_rgb).astype(np.float64)
    resolved = np.all(np.isfinite(all_rgb), axis=1)
    if resolved.sum() < MIN_FIELDS:
        raise InputError(f"charts: {resolved.sum()} fields resolved, expected {MIN_FIELDS}")
    all_rgb = np.maximum(all_rgb[resolved], 0.0)  # dark fields' noise
    all_fields = np.concatenate(reflectances)[resolved]
    illuminant = led.on(grid)
    result: CharacterizationResult = estimate_response(
        all_rgb,
        all_fields,
        illuminant,
        grid.wavelengths_nm,
        method="extended",
        field_positions=np.concatenate(positions)[resolved],
        prior=prior,
        return_details=True,
    )
    residual = fit_residuals(all_rgb, all_fields, illuminant, grid.wavelengths_nm, result)
    values = result.response / result.response.max(axis=0)
    return CameraResponse(values, float(100 * np.sqrt(np.mean(residual**2))), centre_pixels)


def response_weights(measured: dict[str, CameraResponse]) -> dict[str, float]:
    """Per camera its weight in :func:`combined_response`: the inverse square of its chart fit's
    residual (at least :data:`RESIDUAL_FLOOR_PCT`), normalized to a sum of one.

    Examples
    --------
    >>> response_weights({"a": CameraResponse(np.ones((2, 3)), 1.0),
    ...                   "b": CameraResponse(np.ones((2, 3)), 2.0)})
    {'a': 0.8, 'b': 0.2}
    """
    residual = np.array([max(m.fit_residual_pct, RESIDUAL_FLOOR_PCT) for m in measured.values()])
    weights = residual**-2 / np.sum(residual**-2)
    return {camera: round(float(w), 12) for camera, w in zip(measured, weights, strict=True)}


def combined_response(
    measured: dict[str, CameraResponse], led: np.ndarray, white: np.ndarray
) -> tuple[np.ndarray, np.ndarray]:
    """:math:`R_{cam}` ``(K, 3)`` of the dome's RGB cameras (one model) and its standard error:
    the mean of each camera's :func:`band_response`, weighted by the inverse square of its chart
    fit's residual (at least :data:`RESIDUAL_FLOOR_PCT`), so that a camera that sees the chart
    at a grazing angle, its fields a pixel wide, counts little.

    Examples
    --------
    >>> flat = CameraResponse(np.ones((4, 3)), 1.0)
    >>> tilted = CameraResponse(np.linspace(0.5, 1, 4)[:, None] * np.ones(3), 10.0)
    >>> mean, error = combined_response({"a": flat, "b": tilted}, np.ones(4), np.ones(4))
    >>> mean[:, 0].round(3).tolist(), bool(error.max() < 0.01)
    ([0.249, 0.25, 0.25, 0.251], True)
    """
    per_camera = np.array([band_response(m.values, led, white) for m in measured.values()])
    weights = np.array(list(response_weights(measured).values()))
    mean = np.tensordot(weights, per_camera, axes=1)
    if len(per_camera) < 2:
        return mean, np.zeros_like(mean)
    scatter = np.tensordot(weights, (per_camera - mean) ** 2, axes=1)
    effective = 1 / np.sum(weights**2)
    return mean, np.sqrt(scatter / max(effective - 1, 1.0))
