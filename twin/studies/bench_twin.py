"""The twin of a real bench: its frames read through an ingest mapping, its chart rendered where
the camera saw it and lit where the fit put the lamp, and every frame predicted by the camera
model and the data set's own reduction.

:func:`bench_twin` renders the chart with the lamp where the bench file puts it, fits the lamp
(:mod:`twin.studies.bench_fit`) on the declared frames, renders again with the fitted lamp and
refits its powers on the same pixels, and fits the dark signal on the declared dark frames.
:class:`BenchTwin` then gives any frame, noise-free (:meth:`BenchTwin.expected_frame`) or as the
camera records and the data set reduces it (:meth:`BenchTwin.simulate_frame`).
"""

from __future__ import annotations

import tempfile
from dataclasses import dataclass
from functools import cached_property
from pathlib import Path

import cv2
import numpy as np
from skimage import io as skimage_io

from hwbridge.replay import ingest
from recon.calibration.capture_io import select_frames
from recon.chart_patches import patch_masks
from recon.errors import DamagedDataError, InputError
from recon.measured_data import read_spectra_columns
from recon.spectra import SampledSpectra
from twin.render.bench_scene import render_chart_bench
from twin.rigs.bench_config import BenchConfig
from twin.rigs.camera_config import CameraConfig, load_camera_config
from twin.sensor.model import Sensor, bayer_channel_index, mosaic_channels
from twin.sensor.reduced_copy import reduce_raw_frame
from twin.studies.bench_fit import (
    DarkFit,
    LampFit,
    camera_with_dark,
    chart_pose,
    fit_dark,
    fit_lamp,
    fit_pixels,
    stored_per_raw_dn,
)

__all__ = ["BenchTwin", "RealCapture", "bench_twin", "check_bench", "read_real_capture"]

_SPECTRAL_RANGE_NM = (380.0, 780.0)


@dataclass(frozen=True, eq=False)
class RealCapture:
    """A bench's real frames as its capture store holds them.

    ``chart_frames`` ``(n, H, W)`` with their ``band_nm`` and ``exposure_s`` ``(n,)``;
    ``dark_frames`` ``(m, H, W)`` with their ``dark_exposure_s`` ``(m,)``.
    """

    chart_frames: np.ndarray
    band_nm: np.ndarray
    exposure_s: np.ndarray
    dark_frames: np.ndarray
    dark_exposure_s: np.ndarray


def read_real_capture(bench: BenchConfig) -> RealCapture:
    """The bench's frames, read into a capture store by its ingest mapping
    (:func:`hwbridge.replay.ingest`) and out of it as calibration reads any store."""
    with tempfile.TemporaryDirectory() as folder:
        store = ingest(bench.data_folder(), bench.mapping, Path(folder) / "bench.capture.zarr")
        camera = store.metadata.plan[0].camera
        chart = select_frames(store, camera, kind="chart")
        dark = select_frames(store, camera, kind="dark")
    shape = (bench.reduction.height, bench.reduction.width)
    if chart.frames.shape[1:] != shape or dark.frames.shape[1:] != shape:
        raise DamagedDataError(
            f"{bench.data_folder()}: expected frames of {shape[0]}x{shape[1]} px as the bench's "
            f"reduction says, got {chart.frames.shape[1:]}"
        )
    unknown = sorted({int(round(band)) for band in chart.band_nm} - set(bench.filters.columns))
    if unknown:
        raise DamagedDataError(f"{bench.name}: frames at bands {unknown} nm have no filter")
    return RealCapture(chart.frames, chart.band_nm, chart.exposure_s, dark.frames, dark.exposure_s)


def _passbands(bench: BenchConfig, bands_nm: tuple[int, ...]) -> SampledSpectra:
    """The filters' measured transmissions, zero beyond ``main_lobe_nm`` of each peak (the
    spectrometer's floor, not the filters' optical density 4)."""
    columns = tuple(bench.filters.columns[band] for band in bands_nm)
    measured = read_spectra_columns(
        bench.file(bench.filters.spectra),
        columns,
        low_nm=_SPECTRAL_RANGE_NM[0],
        high_nm=_SPECTRAL_RANGE_NM[1],
    )
    values = np.clip(measured.values, 0, None)
    wavelengths = measured.wavelengths_nm
    for row in values:
        row[np.abs(wavelengths - wavelengths[np.argmax(row)]) > bench.filters.main_lobe_nm] = 0
    return SampledSpectra(measured.grid, values, columns)


@dataclass(frozen=True, eq=False)
class BenchTwin:
    """A bench's twin: what it rendered and fitted, and how it makes frames.

    Attributes
    ----------
    bench, camera
        The bench and its camera, with the fitted dark signal.
    bands_nm
        The filters' nominal bands, in the order of the arrays below.
    rate_dn
        ``(n_filters, H, W, 3)`` stored digital numbers per second with the fitted lamp,
        noise-free.
    channel_index, masks
        The stored frames' Bayer channel per pixel and the patch masks.
    lamp, dark
        The fits.
    pose, pitch_m, pose_rms_px
        The chart's pose, pitch and the pose's residual (:func:`twin.studies.bench_fit.
        chart_pose`).
    """

    bench: BenchConfig
    camera: CameraConfig
    bands_nm: tuple[int, ...]
    rate_dn: np.ndarray
    channel_index: np.ndarray
    masks: np.ndarray
    lamp: LampFit
    dark: DarkFit
    pose: np.ndarray
    pitch_m: float
    pose_rms_px: float

    @cached_property
    def sensor(self) -> Sensor:
        """The camera's sensor, its fixed patterns drawn once for all the frames it makes."""
        return Sensor(self.camera)

    @property
    def top_dn(self) -> int:
        """The stored frames' largest value."""
        return 2**self.bench.reduction.bit_depth - 1

    def filter_index(self, band_nm: float) -> int:
        """Index of a frame's filter in :attr:`bands_nm`."""
        band = int(round(band_nm))
        if band not in self.bands_nm:
            raise InputError(f"band_nm: expected one of {list(self.bands_nm)}, got {band}")
        return self.bands_nm.index(band)

    def expected_frame(self, band_nm: float, exposure_s: float) -> np.ndarray:
        """The noise-free stored frame ``(H, W)`` (float, before clipping) of one filter and
        exposure time."""
        rates = self.rate_dn[self.filter_index(band_nm)]
        return exposure_s * mosaic_channels(rates, self.channel_index)

    def simulate_frame(
        self, band_nm: float | None, exposure_s: float, rng: np.random.Generator
    ) -> np.ndarray:
        """One stored frame as the camera records it and the data set reduces it: the sensor
        model's raw frame at full size (shot, read and fixed-pattern noise, dark signal,
        clipping), then the reduction (:func:`twin.sensor.reduce_raw_frame`). ``band_nm`` None
        gives a dark frame."""
        sensor = self.sensor
        if band_nm is None:
            electrons = np.zeros((sensor.height, sensor.width, 3), np.float32)
        else:
            small = (
                exposure_s
                * self.rate_dn[self.filter_index(band_nm)]
                / _dn_per_electron(self.bench, self.camera)
            )
            electrons = cv2.resize(
                small.astype(np.float32),
                (sensor.width, sensor.height),
                interpolation=cv2.INTER_LINEAR,
            )
        raw = sensor.capture(electrons, exposure_s, rng)
        return reduce_raw_frame(
            raw,
            pattern=self.camera.mosaic,
            raw_bit_depth=self.camera.bit_depth,
            shape=(self.bench.reduction.height, self.bench.reduction.width),
            bit_depth=self.bench.reduction.bit_depth,
        )


def _dn_per_electron(bench: BenchConfig, camera: CameraConfig) -> float:
    """Stored digital numbers per photo-electron: the system gain times the reduction's scale."""
    return camera.system_gain_dn_per_e * stored_per_raw_dn(bench, camera)


def _read_labels(bench: BenchConfig) -> np.ndarray:
    labels = np.asarray(skimage_io.imread(bench.file(bench.chart.labels)))
    shape = (bench.reduction.height, bench.reduction.width)
    count = len(bench.chart.patches)
    if labels.shape != shape or int(labels.max()) != count:
        raise DamagedDataError(
            f"{bench.chart.labels}: expected a {shape[0]}x{shape[1]} image labelling patches "
            f"1-{count}, got {labels.shape} with labels up to {int(labels.max())}"
        )
    return labels


def _colour_camera(camera: CameraConfig) -> CameraConfig:
    if camera.mosaic == "none":
        raise InputError(f"camera {camera.name}: the bench twin needs a colour camera")
    return camera


def check_bench(bench: BenchConfig) -> None:
    """Check, before any work, that the bench's files exist and fit together: its data, its
    camera (a colour one), its label image and its filters' spectra."""
    bench.require_files()
    _colour_camera(load_camera_config(bench.camera))
    _read_labels(bench)
    _passbands(bench, tuple(sorted(bench.filters.columns)))


def bench_twin(
    bench: BenchConfig,
    real: RealCapture,
    *,
    camera: CameraConfig | None = None,
    dark: DarkFit | None = None,
    spp: int = 64,
    seed: int = 0,
) -> BenchTwin:
    """Render a bench, fit its free parameters on the declared frames and return its twin.

    Parameters
    ----------
    bench
        The bench.
    real
        Its frames (:func:`read_real_capture`): the fits read only the declared ones.
    camera
        The camera, by default the bench's; another camera (another spectral response) shows
        how much the prediction rests on it.
    dark
        A dark-signal fit to reuse (of the same camera's dark frames); fitted when ``None``.
    spp, seed
        Samples per pixel and seed of the renders.
    """
    camera = _colour_camera(camera or load_camera_config(bench.camera))
    labels = _read_labels(bench)
    shape = labels.shape
    focal_px = (
        bench.focal_length_mm * 1e-3 / (camera.pixel_pitch_um * 1e-6 * bench.reduction.factor)
    )
    pose, pitch_m, rms_px = chart_pose(
        labels, columns=bench.chart.columns, distance_m=bench.chart.distance_m, focal_px=focal_px
    )
    measured = read_spectra_columns(
        bench.file(bench.chart.spectra),
        bench.chart.patches,
        low_nm=_SPECTRAL_RANGE_NM[0],
        high_nm=_SPECTRAL_RANGE_NM[1],
    )
    reflectances = SampledSpectra(measured.grid, np.clip(measured.values, 0, 1), measured.names)
    bands_nm = tuple(sorted({int(round(band)) for band in real.band_nm}))
    passbands = _passbands(bench, bands_nm)
    sensor = Sensor(camera)
    channels = SampledSpectra(
        reflectances.grid,
        np.concatenate(
            [
                sensor.electron_responses(
                    reflectances.grid, SampledSpectra(passbands.grid, row)
                ).values
                for row in passbands.values
            ]
        ),
    )
    per_electron = _dn_per_electron(bench, camera)

    def render(lamp_m: np.ndarray) -> np.ndarray:
        image = render_chart_bench(
            reflectances,
            channels,
            columns=bench.chart.columns,
            pitch_m=pitch_m,
            patch_fill=bench.chart.patch_fill,
            chart_to_camera=pose,
            focal_px=focal_px,
            image_px=shape,
            lamp_position_m=tuple(lamp_m),
            spp=spp,
            seed=seed,
        )
        return image.reshape(*shape, len(bands_nm), 3).transpose(2, 0, 1, 3) * per_electron

    channel_index = bayer_channel_index(shape[0], shape[1], camera.mosaic)
    masks = patch_masks(labels, len(bench.chart.patches), erode_px=bench.chart.erode_px)
    fit_masks = masks[[bench.chart.patches.index(name) for name in bench.fit.patches]]

    def pixels_for(rate_dn: np.ndarray) -> list:
        found = []
        for index, band in enumerate(bands_nm):
            mine = np.flatnonzero(np.isclose(real.band_nm, band))
            found.append(
                fit_pixels(
                    bench,
                    real.chart_frames[mine],
                    real.exposure_s[mine],
                    rate_dn[index],
                    fit_masks,
                    channel_index,
                )
            )
        return found

    start = np.asarray(bench.lamp.position_m, np.float64)
    first = render(start)
    lamp = fit_lamp(bench, pixels_for(first), pose=pose, focal_px=focal_px, shape=shape)
    rate_dn = render(lamp.position_m) if bench.lamp.fit_position else first
    # The powers again, on the render with the lamp where the fit put it (position kept).
    refit = [np.mean(item.log_ratio) for item in pixels_for(rate_dn)]
    lamp = LampFit(
        position_m=lamp.position_m,
        log_power=np.array(refit),
        fit_exposure_s=lamp.fit_exposure_s,
        pixels=lamp.pixels,
        rms_log=lamp.rms_log,
    )
    rate_dn = rate_dn * np.exp(lamp.log_power)[:, None, None, None]
    dark = dark or fit_dark(bench, camera, real.dark_frames, real.dark_exposure_s)
    return BenchTwin(
        bench=bench,
        camera=camera_with_dark(
            camera,
            dark.dark_current_e_per_s,
            dark.dsnu_sigma,
            dark.defect_pixel_fraction,
            dark.defect_offset_dn,
        ),
        bands_nm=bands_nm,
        rate_dn=rate_dn,
        channel_index=channel_index,
        masks=masks,
        lamp=lamp,
        dark=dark,
        pose=pose,
        pitch_m=pitch_m,
        pose_rms_px=rms_px,
    )
