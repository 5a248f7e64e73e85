"""Calibration of the LED dome from a ``dome-calibration`` capture store (thesis 10.3).

From the store's frames (layout: :mod:`hwbridge.dome_layout`), without a renderer:

1. every camera's geometry: intrinsics and world pose from the checkerboard frames
   (:mod:`recon.calibration.dome_geometric`), checked against the store's nominal cameras;
2. the spectral camera's low-SNR calibration (:func:`recon.calibration.dome
   .calibrate_spectral_camera`): dark frames averaged per exposure time, the filtered Robertson
   recovery on the colour checker's series in the reference band (Eq. 10.4-10.8), and the band
   sensitivities :math:`E_\\lambda` from the white standard under the calibration LED through
   every band, over the pixels that see the white standard;
3. every RGB camera's inverse OECF (Robertson on its series of the colour checker) and dark
   level per raw pixel (:func:`recon.calibration.dome.rgb_camera_response`);
4. per LED and camera the white standard's linear values over the sample's area, rectified by
   the calibrated camera and fitted by the LED's irradiance field
   (:mod:`recon.calibration.dome_lighting`): the white reference of every image
   (:math:`V_c = x_c / x^{white}_c`, 10.3) and the irradiance of every spectral image;
5. the LED spectrum from the spectrometer's readings of the white standard, and each RGB
   camera's spectral response from its response series of the colour chart by the chapter 9
   estimator (:mod:`recon.calibration.dome_spectra`); :math:`R_{cam}` per band their product,
   averaged over the cameras and scaled so that the white standard reads one.

The result, :class:`DomeCalibration`, is saved as one ``.npz`` file (the dark frames are images)
with a JSON summary inside; :mod:`recon.dome` processes dome runs with it.

References
----------
- The thesis, section 10.3 (calibration), chapter 9 (the RGB cameras' response) and Eq. 10.1
  (:math:`R_{cam}`: the camera's sensitivity times the light).
"""

from __future__ import annotations

import json
import os
import zipfile
from collections.abc import Callable
from dataclasses import dataclass, replace
from pathlib import Path
from typing import cast

import numpy as np

from hwbridge.dome_layout import SPECTRAL_CAMERA
from hwbridge.schema import (
    DomeGeometry,
    DomeHolder,
    DomeRigAttrs,
    RigAttrs,
    recorded,
)
from hwbridge.store import CaptureStore
from recon.calibration.capture_io import plan_frames, select_frames
from recon.calibration.dome import (
    RgbCameraCalibration,
    SpectralCameraCalibration,
    calibrate_spectral_camera,
    rgb_camera_response,
)
from recon.calibration.dome_geometric import (
    CameraGeometry,
    GeometricCalibration,
    calibrate_camera_geometry,
    stage_rotation,
)
from recon.calibration.dome_lighting import field_scale, led_irradiance
from recon.calibration.dome_spectra import (
    MIN_FIELDS,
    CameraResponse,
    MeasuredLedSpectrum,
    chart_field_rgb,
    combined_response,
    measured_camera_response,
    measured_led_spectrum,
    rig_spectrum,
    square_region,
)
from recon.camera_char import MeasuredPrior
from recon.camera_prior import ResponsePrior
from recon.errors import InputError, Remedy
from recon.progress import progress_steps
from recon.radiometric.demosaic import demosaic
from recon.registration.border import extract_texture
from recon.registration.sample_plane import texel_centres_m
from recon.spectra import WavelengthGrid

__all__ = [
    "DOME_FORMAT",
    "DomeCalibration",
    "calibrate_dome",
    "dome_rig",
    "reference_band_nm",
    "rgb_linear_image",
]

DOME_FORMAT = "spectwin-dome-calibration"
"""The ``format`` of a saved :class:`DomeCalibration`."""

WHITE_TEXELS = 24
"""Texels across the white standard's rectified square, for the fits of its field."""

WHITE_FRACTION = 0.9
"""Fraction of the white standard's square (the holder's opening) that the fits use."""

SERIES_SIGMA_PX = 2.0
"""Gaussian filter of the spectral camera's filtered Robertson recovery (Eq. 10.4)."""

_CAPTURE_REMEDY = {
    "dome-calibration": Remedy.capture_dome_calibration,
    "dome-run": Remedy.capture_dome_run,
}


def dome_rig(store: CaptureStore, program: str) -> DomeRigAttrs:
    """The ``rig`` attribute of a dome capture made by ``program`` (``dome-calibration`` or
    ``dome-run``); anything else is refused, naming what it is or lacks."""
    try:
        recorded: RigAttrs | None = store.rig_attrs(RigAttrs)
    except InputError:
        recorded = None
    if recorded is None or (recorded.rig, recorded.program) != ("dome", program):
        raise InputError(
            f"{store.path}: expected a capture of the dome by program {program}, got program "
            f"{getattr(recorded, 'program', None)!r}",
            remedy=_CAPTURE_REMEDY[program],
        )
    return store.rig_attrs(DomeRigAttrs)


def rgb_linear_image(calibration: RgbCameraCalibration, frames: np.ndarray) -> np.ndarray:
    """Linear, dark-subtracted RGB ``(2H, 2W, 3)`` of one image's raw HDR set ``(n, 2H, 2W)``:
    merged (Eq. 10.3), then demosaiced (``colour-demosaicing``, Malvar et al. 2004)."""
    return demosaic(calibration.linear_mosaic(frames), method="Malvar2004")


@dataclass(frozen=True)
class DomeCalibration:
    """The dome's cameras calibrated (module docstring).

    Attributes
    ----------
    source
        The calibration capture store.
    bands_nm, led_per_band, white_per_band
        ``(K,)`` the bands, the LED's spectrum and the white standard's reflectance in them.
    reference_band_nm
        The spectral camera's band of its response series and per-LED white frames.
    leds
        ``(n,)`` the LEDs the white standard was photographed under.
    spectral
        The spectral camera's dark model, inverse OECF and sensitivities :math:`E_\\lambda`.
    spectral_white
        ``(n,)`` per LED, the scale of its irradiance field in the spectral camera's reference
        band (linear rate per unit :func:`recon.calibration.dome_lighting.led_irradiance`).
    rgb
        Per RGB camera its inverse OECF, HDR set and dark level.
    rgb_white
        Per RGB camera ``(n, 3)``: per LED the white standard's linear RGB per unit irradiance.
    geometry
        Per camera its geometric calibration.
    nominal_deviation
        Per camera how far the calibrated camera lies from the store's nominal one.
    response
        ``(K, 3)`` :math:`R_{cam}`: the mean of the RGB cameras' (:func:`recon.calibration
        .dome_spectra.band_response` of each camera's measured response and the LED spectrum).
    window_px
        Side of the cameras' stored windows.
    led_spectrum
        The LEDs' spectrum measured on the white standard, with its uncertainty and the spread
        over the LEDs.
    camera_response
        Per RGB camera that resolves the charts' fields its measured spectral response ``(K, 3)``
        (peak one per channel) and the chart fit's residual.
    """

    source: str
    bands_nm: np.ndarray
    led_per_band: np.ndarray
    white_per_band: np.ndarray
    reference_band_nm: float
    leds: np.ndarray
    spectral: SpectralCameraCalibration
    spectral_white: np.ndarray
    rgb: dict[str, RgbCameraCalibration]
    rgb_white: dict[str, np.ndarray]
    geometry: dict[str, GeometricCalibration]
    nominal_deviation: dict[str, dict[str, float]]
    response: np.ndarray
    window_px: int
    led_spectrum: MeasuredLedSpectrum
    camera_response: dict[str, CameraResponse]

    @property
    def grid(self) -> WavelengthGrid:
        return WavelengthGrid(self.bands_nm)

    def led_index(self, led: int) -> int:
        """Row of LED ``led`` in :attr:`spectral_white` and :attr:`rgb_white`."""
        rows = np.flatnonzero(self.leds == led)
        if rows.size == 0:
            raise InputError(
                f"LED {led}: not calibrated (the calibration has LEDs {self.leds.tolist()}); "
                "calibrate with the run's LEDs"
            )
        return int(rows[0])

    def response_uncertainty(self) -> np.ndarray:
        """``(K, 3)`` the standard error of :attr:`response` over the RGB cameras (each
        measured on its own, :func:`recon.calibration.dome_spectra.combined_response`)."""
        return combined_response(self.camera_response, self.led_per_band, self.white_per_band)[1]

    def summary(self) -> dict[str, object]:
        """The calibration in numbers (the JSON inside the saved file)."""
        return {
            "format": DOME_FORMAT,
            "source": self.source,
            "bands_nm": self.bands_nm.tolist(),
            "led_per_band": self.led_per_band.tolist(),
            "white_per_band": self.white_per_band.tolist(),
            "reference_band_nm": self.reference_band_nm,
            "leds": self.leds.tolist(),
            "window_px": self.window_px,
            "spectral_observed_levels": list(self.spectral.observed_levels),
            "spectral_sensitivity": self.spectral.sensitivity.tolist(),
            "spectral_white": self.spectral_white.tolist(),
            "rgb_white": {camera: white.tolist() for camera, white in self.rgb_white.items()},
            "rgb_exposure_s": {c: cal.exposure_s.tolist() for c, cal in self.rgb.items()},
            "response": self.response.tolist(),
            "response_uncertainty": self.response_uncertainty().tolist(),
            "led_spectrum": self.led_spectrum.summary(),
            "camera_response": {
                camera: {
                    "values": measured.values.tolist(),
                    "fit_residual_pct": measured.fit_residual_pct,
                    "centre_pixels": measured.centre_pixels,
                }
                for camera, measured in self.camera_response.items()
            },
            "geometry": {
                camera: {
                    **result.geometry.to_json(),
                    "frames_used": result.frames_used,
                    "frames_total": result.frames_total,
                    "reprojection_rms_px": result.reprojection_rms_px,
                    "fitted": result.fitted,
                }
                for camera, result in self.geometry.items()
            },
            "nominal_deviation": self.nominal_deviation,
        }

    def save(self, path: str | Path) -> Path:
        """Write the calibration as one ``.npz`` file, atomically (a temporary file renamed)."""
        path = Path(path)
        arrays = {
            "summary": np.array(json.dumps(self.summary())),
            "spectral_dark_exposure_s": self.spectral.dark_exposure_s,
            "spectral_mean_dark_frames": self.spectral.mean_dark_frames.astype(np.float32),
            "spectral_inverse_response": self.spectral.inverse_response,
        }
        for camera, calibration in self.rgb.items():
            arrays[f"rgb_inverse_response/{camera}"] = calibration.inverse_response
            arrays[f"rgb_dark/{camera}"] = calibration.dark.astype(np.float32)
        temporary = path.with_name(f".{path.name}.writing")
        with temporary.open("wb") as file:
            # the stub's allow_pickle keyword (a bool) stands in the way of **arrays
            np.savez_compressed(file, **arrays)  # type: ignore[arg-type]
        os.replace(temporary, path)
        return path

    @classmethod
    def load(cls, path: str | Path) -> DomeCalibration:
        """Read a file written by :meth:`save`."""
        path = Path(path)
        try:
            with np.load(path, allow_pickle=False) as file:
                arrays = {name: file[name] for name in file.files}
            summary = json.loads(str(arrays["summary"]))
        except (OSError, ValueError, KeyError, EOFError, zipfile.BadZipFile) as error:
            raise InputError(
                f"{path}: not a dome calibration file ({error})", remedy=Remedy.calibrate
            ) from None
        if summary.get("format") != DOME_FORMAT:
            raise InputError(
                f"{path}: expected a dome calibration (format {DOME_FORMAT}), got "
                f"{summary.get('format')!r}"
            )
        spectral = SpectralCameraCalibration(
            arrays["spectral_dark_exposure_s"],
            arrays["spectral_mean_dark_frames"].astype(np.float64),
            arrays["spectral_inverse_response"],
            tuple(summary["spectral_observed_levels"]),
            np.asarray(summary["spectral_sensitivity"]),
        )
        rgb = {
            camera: RgbCameraCalibration(
                arrays[f"rgb_inverse_response/{camera}"],
                np.asarray(times),
                arrays[f"rgb_dark/{camera}"].astype(np.float64),
                np.ones(3),
            )
            for camera, times in summary["rgb_exposure_s"].items()
        }
        geometry = {
            camera: GeometricCalibration(
                CameraGeometry.from_json(entry),
                entry["frames_used"],
                entry["frames_total"],
                entry["reprojection_rms_px"],
                entry["fitted"],
            )
            for camera, entry in summary["geometry"].items()
        }
        return cls(
            source=summary["source"],
            bands_nm=np.asarray(summary["bands_nm"]),
            led_per_band=np.asarray(summary["led_per_band"]),
            white_per_band=np.asarray(summary["white_per_band"]),
            reference_band_nm=float(summary["reference_band_nm"]),
            leds=np.asarray(summary["leds"], int),
            spectral=spectral,
            spectral_white=np.asarray(summary["spectral_white"]),
            rgb=rgb,
            rgb_white={c: np.asarray(w) for c, w in summary["rgb_white"].items()},
            geometry=geometry,
            nominal_deviation=summary["nominal_deviation"],
            response=np.asarray(summary["response"]),
            window_px=int(summary["window_px"]),
            led_spectrum=MeasuredLedSpectrum.from_summary(summary["led_spectrum"]),
            camera_response={
                camera: CameraResponse(
                    np.asarray(entry["values"]),
                    entry["fit_residual_pct"],
                    bool(entry.get("centre_pixels", False)),
                )
                for camera, entry in summary["camera_response"].items()
            },
        )


def _mean_darks(
    store: CaptureStore, camera: str, times: np.ndarray | None = None
) -> tuple[np.ndarray, np.ndarray]:
    """Dark frames averaged per exposure time (every time the camera's dark frames have, or
    ``times``), read one exposure time at a time."""
    index = store.index(camera, ("kind", "exposure_s"))
    dark = index["kind"] == "dark"
    if times is None:
        times = np.unique(index["exposure_s"][dark])
    means = []
    for exposure in times:
        slots = np.flatnonzero(dark & np.isclose(index["exposure_s"], exposure))
        if slots.size == 0:
            raise InputError(f"{store.path}: no dark frames of camera {camera!r} at {exposure:g} s")
        means.append(store.read_frames(camera, slots).mean(axis=0, dtype=np.float64))
    return np.asarray(times, np.float64), np.stack(means)


class _WhiteSquare:
    """The white standard's central square at stage position 0, as one camera sees it."""

    def __init__(self, geometry: CameraGeometry, holder: DomeHolder):
        side = 2 * WHITE_FRACTION * holder.opening_half_m
        self.points_m = np.concatenate(
            [texel_centres_m(WHITE_TEXELS, side), np.zeros((WHITE_TEXELS, WHITE_TEXELS, 1))],
            axis=-1,
        )
        half = side / 2
        square = np.array([[-half, half, 0], [half, half, 0], [half, -half, 0], [-half, -half, 0]])
        self.corners_xy = geometry.project(square) + 0.5

    def texture(self, image: np.ndarray) -> np.ndarray:
        return extract_texture(image, self.corners_xy, resolution=WHITE_TEXELS)

    def region(self, shape: tuple[int, int]) -> np.ndarray:
        """The pixels ``shape`` whose centres lie on the square."""
        return square_region(self.corners_xy, shape)

    def scale(self, image: np.ndarray, led_position_m: np.ndarray) -> np.ndarray:
        """The scale of the LED's irradiance field in ``image`` (channels last, or one)."""
        values = self.texture(image)
        values = values[..., None] if values.ndim == 2 else values
        return field_scale(values, led_irradiance(self.points_m, led_position_m))


def _geometric_calibration(
    store: CaptureStore,
    geometry: DomeGeometry,
    camera: str,
    nominal: CameraGeometry,
    grey: Callable[[np.ndarray], np.ndarray],
) -> GeometricCalibration:
    target = geometry.geometric_target
    frames, steps = plan_frames(store, camera, kind="geometric")
    poses = []
    for step in steps:
        pose = np.eye(4)
        pose[:3, :3] = stage_rotation(geometry.stage_angles_deg[step.view_id])
        poses.append(pose @ np.asarray(target.target_to_sample[f"{step.tilt_deg:g}"]))
    return calibrate_camera_geometry(
        [grey(frame) for frame in frames],
        poses,
        np.asarray(target.corners_m),
        target.inner_corners,
        nominal,
    )


def _spectral_calibration(
    store: CaptureStore, rig: DomeRigAttrs, white: _WhiteSquare, led: np.ndarray
) -> tuple[SpectralCameraCalibration, np.ndarray]:
    """The spectral camera's calibration and its white scale per LED (module docstring)."""
    bands = np.asarray(rig.bands_nm, np.float64)
    reference = reference_band_nm(store)
    series = select_frames(store, SPECTRAL_CAMERA, kind="oecf", band_nm=reference)
    lit, steps = plan_frames(store, SPECTRAL_CAMERA, kind="white", light_id=rig.calibration_led)
    last = {
        float(recorded(step.band_nm, f"{store.path}: plan step band_nm")): slot
        for slot, step in enumerate(steps)
    }
    slots = [last[float(band)] for band in bands]
    times, means = _mean_darks(store, SPECTRAL_CAMERA)
    spectral = calibrate_spectral_camera(
        times,
        means,
        series.frames,
        series.exposure_s,
        lit[slots],
        np.array([steps[slot].exposure_s for slot in slots]),
        led,
        rig_spectrum(rig.white_reflectance, WavelengthGrid(bands)),
        sigma_px=SERIES_SIGMA_PX,
        bit_depth=rig.geometry.cameras[SPECTRAL_CAMERA].bit_depth,
        white_region=white.region(means.shape[1:]),
    )
    positions = np.asarray(rig.geometry.led_positions_m, np.float64)
    scales = []
    for light in _run_leds(store, rig):
        frames, steps = plan_frames(
            store, SPECTRAL_CAMERA, kind="white", light_id=light, band_nm=reference
        )
        rate = spectral.linear_rate(frames[0], steps[0].exposure_s)
        scales.append(white.scale(rate, positions[light])[0])
    return spectral, np.array(scales)


def reference_band_nm(store: CaptureStore) -> float:
    """The spectral camera's reference band: that of its response series (``oecf``)."""
    index = store.index(SPECTRAL_CAMERA, ("kind", "band_nm"))
    bands = np.unique(index["band_nm"][index["kind"] == "oecf"])
    if bands.size != 1:
        raise InputError(
            f"{store.path}: expected the spectral camera's response series in one band, got "
            f"{bands.tolist()} nm"
        )
    return float(bands[0])


def _run_leds(store: CaptureStore, rig: DomeRigAttrs) -> list[int]:
    """The LEDs the white standard was photographed under, in plan order (module docstring)."""
    leds = [
        step.light_id
        for step in store.metadata.plan
        if step.kind == "white" and step.camera != SPECTRAL_CAMERA
    ]
    return list(dict.fromkeys(leds)) or [rig.calibration_led]


def _rgb_calibration(
    store: CaptureStore, camera: str, rig: DomeRigAttrs, white: _WhiteSquare
) -> tuple[RgbCameraCalibration, np.ndarray]:
    """An RGB camera's response, dark level and white per LED (module docstring)."""
    hdr_set = np.asarray(rig.rgb_exposures_s, np.float64)
    series = select_frames(store, camera, kind="oecf")
    times, darks = _mean_darks(store, camera, np.sort(hdr_set))
    calibration = rgb_camera_response(
        series.frames.astype(np.uint16),
        series.exposure_s,
        darks,
        times,
        hdr_set,
        bit_depth=rig.geometry.cameras[camera].bit_depth,
    )
    positions = np.asarray(rig.geometry.led_positions_m, np.float64)
    scales = []
    for light in _run_leds(store, rig):
        frames, steps = plan_frames(store, camera, kind="white", light_id=light)
        order = [list(hdr_set).index(step.exposure_s) for step in steps]
        image = rgb_linear_image(calibration, frames[np.argsort(order)])
        scales.append(white.scale(image, positions[light]))
    return calibration, np.array(scales)


def _chart_response(
    store: CaptureStore,
    camera: str,
    rig: DomeRigAttrs,
    calibration: RgbCameraCalibration,
    geometry: CameraGeometry,
    led: MeasuredLedSpectrum,
    prior: ResponsePrior | MeasuredPrior | None,
    centre_pixels: bool = False,
) -> CameraResponse | None:
    """An RGB camera's spectral response from its photographs of the charts (module docstring,
    step 5): each chart's frames merged to one linear image, the fields' means, chapter 9;
    ``None`` where the camera resolves fewer than :data:`~recon.calibration.dome_spectra
    .MIN_FIELDS` fields (a grazing view of small fields), unless ``centre_pixels`` takes each
    field's centre pixel (where no camera resolves them)."""
    charts = recorded(rig.charts, f"{store.path}: rig charts")
    position = np.asarray(rig.geometry.led_positions_m, np.float64)[rig.calibration_led]
    field_rgb = []
    for chart in charts:
        frames = select_frames(store, camera, kind=chart.kind)
        merged = replace(calibration, exposure_s=np.asarray(frames.exposure_s, np.float64))
        quads = merged.hdr(frames.frames)  # no demosaicing: no colour bleeding between fields
        field_rgb.append(
            chart_field_rgb(
                quads, geometry, chart, position, binning=2, centre_pixels=centre_pixels
            )
        )
    resolved = np.all(np.isfinite(np.concatenate(field_rgb)), axis=1).sum()
    if not centre_pixels and resolved < MIN_FIELDS:
        return None
    grid = WavelengthGrid(np.asarray(rig.bands_nm, np.float64))
    return measured_camera_response(
        field_rgb, charts, led, grid, prior=prior, centre_pixels=centre_pixels
    )


def calibrate_dome(
    store: str | Path | CaptureStore,
    *,
    show_progress: bool = False,
    camera_prior: ResponsePrior | MeasuredPrior | None = "measured",
) -> DomeCalibration:
    """Calibrate the dome from a ``dome-calibration`` capture (module docstring).

    Parameters
    ----------
    store
        The calibration capture store (complete).
    show_progress
        A progress bar over the cameras.
    camera_prior
        The prior of the RGB cameras' chapter 9 estimates (:func:`recon.camera_char
        .estimate_response`'s ``prior``: by default learned from the measured cameras that ship
        with spectwin).

    Returns
    -------
    DomeCalibration
    """
    store = store if isinstance(store, CaptureStore) else CaptureStore.open(store)
    rig = dome_rig(store, "dome-calibration")
    grid = WavelengthGrid(np.asarray(rig.bands_nm, np.float64))
    led_spectrum = measured_led_spectrum(store, rig)
    led = led_spectrum.on(grid)
    white_reflectance = rig_spectrum(rig.white_reflectance, grid)
    measured: dict[str, CameraResponse] = {}
    cameras = rig.geometry.cameras
    nominal = {camera: CameraGeometry.nominal(entry) for camera, entry in cameras.items()}
    geometry: dict[str, GeometricCalibration] = {}
    rgb: dict[str, RgbCameraCalibration] = {}
    rgb_white = {}

    def chart_response(camera: str, centre_pixels: bool = False) -> CameraResponse | None:
        return _chart_response(
            store,
            camera,
            rig,
            rgb[camera],
            geometry[camera].geometry,
            led_spectrum,
            camera_prior,
            centre_pixels=centre_pixels,
        )

    with progress_steps("calibrate", len(cameras), enabled=show_progress) as advance:
        for camera in cameras:
            grey = _grey_frame(camera)
            geometry[camera] = _geometric_calibration(
                store, rig.geometry, camera, nominal[camera], grey
            )
            white = _WhiteSquare(geometry[camera].geometry, rig.geometry.holder)
            if camera == SPECTRAL_CAMERA:
                spectral, spectral_white = _spectral_calibration(store, rig, white, led)
            else:
                rgb[camera], rgb_white[camera] = _rgb_calibration(store, camera, rig, white)
                response = chart_response(camera)
                if response is not None:
                    measured[camera] = response
            advance()
    if not measured:  # a capture of few texels: every camera from its fields' centre pixels
        for camera in rgb:
            measured[camera] = cast(CameraResponse, chart_response(camera, centre_pixels=True))
    return DomeCalibration(
        source=str(store.path),
        bands_nm=grid.wavelengths_nm.copy(),
        led_per_band=led,
        white_per_band=white_reflectance,
        reference_band_nm=reference_band_nm(store),
        leds=np.asarray(_run_leds(store, rig), int),
        spectral=spectral,
        spectral_white=spectral_white,
        rgb=rgb,
        rgb_white=rgb_white,
        geometry=geometry,
        nominal_deviation={
            camera: result.geometry.deviation_from(nominal[camera])
            for camera, result in geometry.items()
        },
        response=combined_response(measured, led, white_reflectance)[0],
        window_px=rig.window_px,
        led_spectrum=led_spectrum,
        camera_response=measured,
    )


def _grey_frame(camera: str) -> Callable[[np.ndarray], np.ndarray]:
    """A grey image of a raw frame for corner finding: the frame itself, or the mean of its
    demosaiced channels for a Bayer mosaic."""
    if camera == SPECTRAL_CAMERA:
        return lambda frame: frame
    return lambda frame: demosaic(frame, method="bilinear").mean(axis=-1)
