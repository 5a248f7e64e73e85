"""The chapter 10 dome study's frames from dome capture stores (thesis 10.2-10.4).

The study's store path takes its images where a real dome's processing would: from a
``dome-run`` store of the material and a ``dome-calibration`` store of the same LEDs and cameras
(:mod:`twin.dome.programs`, layout :mod:`hwbridge.dome_layout`), read with
:class:`hwbridge.store.CaptureStore`:

1. :func:`capture_study_stores` captures them, rendered by Mitsuba: the run completely, of the
   calibration its dark frames and white-standard frames (the response series and the
   checkerboard frames serve calibrations the study takes from :mod:`twin.dome.setup`);
2. :func:`store_capture` converts the frames. Dark frames averaged per exposure time are
   subtracted, raw values linearized with the inverse responses of the study's calibration
   (:func:`twin.dome.setup.dome_setup`), RGB exposure sets merged (Eq. 10.3) per Bayer quad.
   Every pixel is divided by the white standard under the same LED (RGB: :math:`V` relative to
   the white reference, per unit :math:`\\cos\\theta_i`; spectral: the white through every band
   under the calibration LED, scaled to the image's LED by the white in the reference band,
   times the white's reflectance, thesis 10.3). The holder's marks are found in each camera's
   alignment frame (:func:`recon.registration.border.register_frame`, thesis 4.1.2) and the
   material's square is resampled (:func:`recon.registration.border.extract_texture`) at the
   capture's own resolution and averaged onto ``texels x texels`` texels, a divisor of the
   capture's: two capture texels (Bayer quads at the rig's centre) across a study texel keep
   the bilinear resampling's blur off the texel values.

Images: per stage position and LED one image seen by the RGB camera nearest the spectral camera,
with the bands the schedule gives that LED, and one per other RGB camera, without spectral data
(10.4.2). Their truth is :func:`twin.render.truth.texture_truth` for the images' light and view
directions in the sample frame, as in the analytic path.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from hwbridge.dome_layout import SPECTRAL_CAMERA, camera_steps
from hwbridge.session import capture_steps, locked_session_store
from hwbridge.store import CaptureStore
from recon.calibration.dome import RgbCameraCalibration, SpectralCameraCalibration, texel_mean
from recon.errors import SpectwinInputError
from recon.radiometric.demosaic import bin_quads
from recon.registration.border import MarksNotFoundError, extract_texture, register_frame
from recon.registration.corners import CornerRefinementError, texture_transform
from recon.spectralize.solve import BandImage
from twin.dome.capture_study import DomeCapture
from twin.dome.programs import DomeCaptureSize, dome_calibration_program, dome_run_program
from twin.dome.setup import DomeSetup
from twin.materials import load_material
from twin.materials.textures import TextureTruth
from twin.render.truth import texture_truth

__all__ = ["StoreImages", "capture_study_stores", "store_capture", "store_exposure_ratio"]

_CALIBRATION_KINDS = ("dark", "white")


def capture_study_stores(
    folder: Path,
    material: str,
    size: DomeCaptureSize,
    *,
    seed: int,
    dark_frames: int,
) -> tuple[CaptureStore, CaptureStore]:
    """The ``dome-run`` store of ``material`` and the calibration store of ``size`` in
    ``folder`` (module description), captured where missing, reused where complete."""
    run_path = folder / f"{material}.capture.zarr"
    if not (run_path.exists() and CaptureStore.open(run_path).complete):
        dome_run_program(material, size=size, seed=seed).run(run_path, resume=run_path.exists())
    calibration_path = folder / "calibration.capture.zarr"
    if not calibration_path.exists():
        program = dome_calibration_program(size=size, dark_frames=dark_frames, seed=seed)
        steps = [i for i, step in enumerate(program.plan) if step["kind"] in _CALIBRATION_KINDS]
        devices = program.devices()
        with locked_session_store(
            calibration_path, program.plan, devices, rig=program.rig, backend="sim", seed=seed
        ) as store:
            capture_steps(store, steps, devices, seed=seed)
    return CaptureStore.open(run_path), CaptureStore.open(calibration_path)


def _frames(store: CaptureStore, camera: str, **wanted) -> tuple[np.ndarray, list[dict]]:
    """The frames of ``camera`` whose plan steps have the ``wanted`` settings, in plan order,
    and those steps."""
    plan = store.attrs["plan"]
    order = camera_steps(plan, camera)
    slots = [
        slot
        for slot, step in enumerate(order)
        if all(plan[step].get(key) == value for key, value in wanted.items())
    ]
    if not slots:
        raise SpectwinInputError(f"store {store.path}: no {camera} frames with {wanted}")
    return store.read_frames(camera, slots).astype(np.float64), [plan[order[s]] for s in slots]


def _mean_darks(calibration: CaptureStore, camera: str) -> tuple[np.ndarray, np.ndarray]:
    """Exposure times ``(n,)`` and dark frames averaged per time ``(n, H, W)``."""
    frames, steps = _frames(calibration, camera, kind="dark")
    exposures = np.array([step["exposure_s"] for step in steps])
    times = np.unique(exposures)
    return times, np.stack([frames[exposures == t].mean(axis=0) for t in times])


@dataclass(frozen=True)
class _Converters:
    """Raw frames to linear values with the store's dark frames and the study's curves."""

    rgb: RgbCameraCalibration
    spectral: SpectralCameraCalibration

    @classmethod
    def of(cls, setup: DomeSetup, calibration: CaptureStore, rgb_camera: str) -> _Converters:
        rig = calibration.attrs["rig"]
        hdr_s = np.asarray(rig["rgb_exposures_s"])
        times, darks = _mean_darks(calibration, rgb_camera)
        dark_set = np.stack([darks[np.argmin(np.abs(times - t))] for t in hdr_s])
        no_dark = RgbCameraCalibration(setup.rgb.inverse_response, hdr_s, 0.0, np.ones(3))
        rgb = RgbCameraCalibration(
            setup.rgb.inverse_response, hdr_s, no_dark.hdr(dark_set), np.ones(3)
        )
        times, darks = _mean_darks(calibration, SPECTRAL_CAMERA)
        spectral = SpectralCameraCalibration(
            times,
            darks,
            setup.spectral.inverse_response,
            setup.spectral.observed_levels,
            np.ones(len(rig["bands_nm"])),
        )
        return cls(rgb, spectral)


def _material_corners(run: CaptureStore, frame: np.ndarray, camera: str, view: int) -> np.ndarray:
    """Image corners ``(4, 2)`` of the material's square in ``frame`` (an alignment frame; RGB
    in Bayer quads), from the holder's marks found near the metadata's nominal points (the
    nominal points themselves where the frame is too small to refine them: under about 24
    texels, the RGB cameras' quads leave a few pixels across the print)."""
    geometry = run.attrs["rig"]["geometry"]
    nominal = np.asarray(geometry["cameras"][camera]["marker_corners_xy"][str(view)])
    mark_half = float(np.abs(np.asarray(geometry["holder"]["registration_corners_m"])[0, 0]))
    # the metadata counts from the pixels' centres, register_frame and extract_texture from
    # their edges
    edges = nominal + 0.5 if camera == SPECTRAL_CAMERA else (nominal + 0.5) / 2
    try:
        marks = register_frame(frame, expected_xy=edges)
    except (CornerRefinementError, MarksNotFoundError):  # too few pixels: the metadata's
        marks = edges
    reach = load_material(run.attrs["rig"]["material"]).size_m / (4 * mark_half)
    low, high = 0.5 - reach, 0.5 + reach
    square = np.array([[low, low], [high, low], [high, high], [low, high]])
    return texture_transform(marks).inverse(square)


@dataclass(frozen=True)
class StoreImages:
    """The study's images from stores: the capture (as the analytic path builds it), the
    texture truth, and per image the light direction in the sample frame, the bands taken, the
    LED and the RGB camera it came from (what the analytic path needs to take the same
    images)."""

    capture: DomeCapture
    truth: TextureTruth
    light_dirs: np.ndarray
    bands_per_image: list[list[int]]
    leds: list[int]
    cameras: list[str]


def _sample_frame(run: CaptureStore, view: int, position_m) -> np.ndarray:
    """Unit direction of a world position seen from the sample, in the sample frame."""
    turn = math.radians(run.attrs["rig"]["geometry"]["stage_angles_deg"][view])
    x, y, z = np.asarray(position_m, np.float64) / np.linalg.norm(position_m)
    return np.array(
        [x * math.cos(turn) + y * math.sin(turn), -x * math.sin(turn) + y * math.cos(turn), z]
    )


def _white_reflectance(rig: dict) -> np.ndarray:
    white = rig["white_reflectance"]
    return np.interp(rig["bands_nm"], white["wavelengths_nm"], white["values"])


def store_capture(
    setup: DomeSetup,
    run: CaptureStore,
    calibration: CaptureStore,
    texels: int,
    *,
    step: Callable[[str], None] = lambda name: None,
) -> StoreImages:
    """The images of a ``dome-run`` store converted with its calibration store (module
    description)."""
    rig = run.attrs["rig"]
    if rig.get("program") != "dome-run" or calibration.attrs["rig"].get("program") != (
        "dome-calibration"
    ):
        raise SpectwinInputError(
            f"stores {run.path}, {calibration.path}: expected a dome-run and a dome-calibration "
            "store"
        )
    if texels < 1 or rig["texels"] % texels:
        raise SpectwinInputError(
            f"texels: expected a divisor of the capture's {rig['texels']} texels, got {texels}"
        )

    def resampled(image: np.ndarray, corners: np.ndarray) -> np.ndarray:
        fine = extract_texture(image, corners, resolution=rig["texels"])
        return texel_mean(fine, rig["texels"] // texels)

    geometry = rig["geometry"]
    rgb_cameras = sorted(c for c in geometry["cameras"] if c != SPECTRAL_CAMERA)
    spectral_at = np.asarray(geometry["cameras"][SPECTRAL_CAMERA]["position_m"])
    paired = min(
        rgb_cameras,
        key=lambda c: np.linalg.norm(
            np.asarray(geometry["cameras"][c]["position_m"]) - spectral_at
        ),
    )
    order = [paired] + [c for c in rgb_cameras if c != paired]
    bands_nm = list(rig["bands_nm"])
    reference = bands_nm.index(float(calibration.attrs["rig"].get("reference_band_nm", 550.0)))
    converters = {c: _Converters.of(setup, calibration, c) for c in rgb_cameras}
    spectral = converters[paired].spectral
    cal_led = int(calibration.attrs["rig"]["calibration_led"])
    white_frames, white_steps = _frames(
        calibration, SPECTRAL_CAMERA, kind="white", light_id=cal_led
    )
    white_band = {
        bands_nm.index(s["band_nm"]): spectral.linear_rate(f, s["exposure_s"])
        for f, s in zip(white_frames, white_steps, strict=True)
    }
    white_rho = _white_reflectance(rig)
    sigma = setup.filter_sigma()
    views = sorted({s["view_id"] for s in run.attrs["plan"] if s["kind"] == "alignment"})
    images: list[tuple[int, int, str]] = []
    rgb, band_images, lights, seen_from = [], [], [], []
    spectral_s = 0.0
    for camera in order:
        step(f"reading {camera}")
        convert = converters[camera]
        leds_white, steps_white = _frames(calibration, camera, kind="white")
        for view in views:
            alignment, _ = _frames(run, camera, kind="alignment", view_id=view)
            corners = _material_corners(run, bin_quads(alignment[0]).mean(-1), camera, view)
            sample, sample_steps = _frames(run, camera, kind="sample", view_id=view)
            hdr_sets = len(rig["rgb_exposures_s"])
            for first in range(0, len(sample_steps), hdr_sets):
                led = int(sample_steps[first]["light_id"])
                whites = [i for i, s in enumerate(steps_white) if s["light_id"] == led]
                ratio = convert.rgb.hdr(sample[first : first + hdr_sets]) / convert.rgb.hdr(
                    leds_white[whites]
                )
                rgb.append(resampled(ratio, corners))
                lights.append(_sample_frame(run, view, geometry["led_positions_m"][led]))
                seen_from.append(
                    _sample_frame(run, view, geometry["cameras"][camera]["position_m"])
                )
                images.append((view, led, camera))
    step("reading spectral")
    for view in views:
        alignment, _ = _frames(run, SPECTRAL_CAMERA, kind="alignment", view_id=view)
        corners = _material_corners(run, alignment[0], SPECTRAL_CAMERA, view)
        frames, steps = _frames(run, SPECTRAL_CAMERA, kind="sample", view_id=view)
        for frame, settings in zip(frames, steps, strict=True):
            led, band = int(settings["light_id"]), bands_nm.index(settings["band_nm"])
            white_led, white_step = _frames(
                calibration,
                SPECTRAL_CAMERA,
                kind="white",
                light_id=led,
                band_nm=bands_nm[reference],
            )
            led_scale = (
                spectral.linear_rate(white_led[0], white_step[0]["exposure_s"])
                / (white_band[reference])
            )
            rho = spectral.linear_rate(frame, settings["exposure_s"]) / (
                white_band[band] * led_scale
            )
            image = images.index((view, led, paired))
            values = resampled(rho * white_rho[band], corners)
            band_images.append(BandImage(image, band, values, float(sigma[band])))
            spectral_s += float(settings["exposure_s"])
    truth = texture_truth(rig["material"], np.array(lights), np.array(seen_from), texels=texels)
    capture = DomeCapture(
        setup.cameras.band_reflectance(truth), np.stack(rgb), tuple(band_images), spectral_s
    )
    bands: list[list[int]] = [[] for _ in images]
    for band_image in band_images:
        bands[band_image.image].append(band_image.band)
    return StoreImages(
        capture,
        truth,
        np.array(lights),
        bands,
        [led for _, led, _ in images],
        [camera for *_, camera in images],
    )


def store_exposure_ratio(
    run: CaptureStore, calibration: CaptureStore, *, max_dn: int
) -> dict[str, float]:
    """Thesis 10.5's exposure totals from the stores: the hybrid image (the run's HDR set and
    every band at the run's exposures, one after the other) against spectral-only band frames
    that bring the white standard facing the LED to 80 % of the spectral camera's range (its
    white frames through every band under the calibration LED, dark-subtracted); ``max_dn`` is
    the spectral camera's largest raw value."""
    rig, cal_rig = run.attrs["rig"], calibration.attrs["rig"]
    led = int(cal_rig["calibration_led"])
    cos_i = float(np.asarray(cal_rig["geometry"]["led_positions_m"][led])[2]) / float(
        np.linalg.norm(cal_rig["geometry"]["led_positions_m"][led])
    )
    times, darks = _mean_darks(calibration, SPECTRAL_CAMERA)
    frames, steps = _frames(calibration, SPECTRAL_CAMERA, kind="white", light_id=led)
    reference = {}
    for frame, settings in zip(frames, steps, strict=True):
        dark = darks[np.argmin(np.abs(times - settings["exposure_s"]))]
        centre = slice(frame.shape[0] // 2 - 4, frame.shape[0] // 2 + 4)
        rate = float((frame - dark)[centre, centre].mean()) / settings["exposure_s"] / cos_i
        headroom = max_dn - float(dark[centre, centre].mean())
        reference[settings["band_nm"]] = 0.8 * headroom / rate
    hybrid_s = sum(rig["rgb_exposures_s"]) + sum(rig["band_exposures_s"])
    reference_s = sum(reference.values())
    return {
        "hybrid_total_s": hybrid_s,
        "reference_total_s": reference_s,
        "orders_of_magnitude": math.log10(reference_s / hybrid_s),
    }
