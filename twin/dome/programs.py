"""Capture programs of the simulated LED dome (thesis 10.2-10.4), every frame rendered.

Two programs, as on the real rig (plans: :mod:`hwbridge.dome_plans`; store layout:
:mod:`hwbridge.dome_layout`):

1. ``dome-calibration``: dark frames (200 per spectral exposure by default), response series of
   the colour checker, the white standard under the LEDs, and the checkerboard flat and on a
   30 degree wedge at eight stage positions;
2. ``dome-run``: per stage position an alignment frame of every camera with all LEDs on, then
   per LED the RGB cameras' HDR sets and the spectral camera's scheduled noisy bands.

Every frame is rendered (:class:`twin.dome.signals.RenderedDomeSignal`: one render per stage
position, LEDs, holder content and camera, reused for every exposure and band; by default the
LEDs lit one at a time rendered together, in passes per camera and stage position) and turned
into a raw frame by the camera's sensor model (a Bayer mosaic for the RGB cameras). The
exposures come from the rig and camera models (:mod:`twin.dome.exposure_plan`). A reduced capture
(:class:`DomeCaptureSize`) takes the first stage positions, LEDs spread over the dome and RGB
cameras spread over the arc.

A program is built (:func:`dome_calibration_program`, :func:`dome_run_program`) before anything
is written: building checks its settings; :meth:`DomeCaptureProgram.dry_run` describes it and
:meth:`DomeCaptureProgram.run` captures it, resumably, in this process or over a Dask cluster.
"""

from __future__ import annotations

from collections import Counter
from dataclasses import dataclass
from typing import Any

import numpy as np

from hwbridge.dome_layout import ALL_LEDS, SPECTRAL_CAMERA, rgb_camera_id
from hwbridge.dome_plans import (
    DomeCameraIds,
    DomeExposures,
    DomeTiming,
    dome_calibration,
    dome_duration_s,
    dome_run,
    dome_start_times_s,
)
from hwbridge.schema import NO_LIGHT, NO_VIEW, DomeRigAttrs, Spectrum
from hwbridge.store import CaptureStore
from recon.errors import InputError
from recon.spectra import WavelengthGrid
from twin.components.targets import zenith_white_reflectance
from twin.devices.dome_spectrometer import SPECTROMETER_GRID, DomeSpectrometer
from twin.devices.programs import (
    ProgramCapture,
    check_exposures,
    check_fault_rate,
    check_seed,
    is_whole,
)
from twin.devices.sim_devices import SimDomeDevices
from twin.dome.capture_geometry import FrameSize, camera_arc_index, geometry_metadata
from twin.dome.exposure_plan import dome_exposures
from twin.dome.holder import chart_geometry, holder_content
from twin.dome.render import DOME_SPP
from twin.dome.setup import CALIBRATION_LIGHT, THESIS_LONGEST_BAND_S
from twin.dome.signals import (
    LED_RENDERS,
    DomeScene,
    RenderedDomeSignal,
    band_index,
    leds_per_pass,
)
from twin.materials import available_materials, load_material
from twin.rigs.dome_geometry import dome_geometry
from twin.rigs.rig_config import DomeConfig, load_rig
from twin.sensor.model import Sensor

__all__ = [
    "CERTIFICATE_GRID",
    "DEFAULT_SPP",
    "LED_FULL_SCALE_MA",
    "GEOMETRIC_VIEWS",
    "DomeCaptureProgram",
    "DomeCaptureSize",
    "DomePlanParts",
    "calibration_led",
    "calibration_plan",
    "dome_calibration_program",
    "dome_plan_parts",
    "dome_run_program",
    "dome_timing",
    "run_plan",
    "stored_dome_settings",
]

GEOMETRIC_VIEWS = ((0.0, 0.0), *((turn / 8, 30.0) for turn in range(8)))
"""Geometric calibration frames: (fraction of a stage turn, wedge tilt in degrees): the
checkerboard flat, then on a 30 degree wedge at eight stage angles 45 degrees apart, so that
every camera sees it in up to nine plane orientations (the oblique cameras lose those where the
wedge turns the board away from them)."""

RGB_DARK_FRAMES = 16
"""Most dark frames per exposure time of an RGB camera (its darks serve the HDR merge only)."""

CERTIFICATE_GRID = WavelengthGrid.regular(380.0, 780.0, 5.0)
"""Wavelengths of the certificates a calibration store records (the white standard's and the
colour chart's reflectance), as a certificate gives them: 380-780 nm in 5 nm steps."""

LED_FULL_SCALE_MA = 700.0
"""The LED drivers' full scale, at which the dome's LEDs emit their nominal intensity (the
drive current of every frame of the programs)."""

DEFAULT_SPP = DOME_SPP
"""Samples per pixel of the dome's renders by default (``--spp``, :data:`twin.dome.render.
DOME_SPP`)."""


def _spread(count: int, total: int) -> list[int]:
    """``count`` indices spread evenly over ``0 .. total - 1``, the first and last included."""
    if count == 1:
        return [0]
    return np.round(np.linspace(0, total - 1, count)).astype(int).tolist()


@dataclass(frozen=True)
class DomeCaptureSize:
    """The size of a dome capture: the rig's full procedure by default, or a reduced one.

    Attributes
    ----------
    stage_positions
        The first stage positions (15 degree steps), at most the rig's 24.
    leds
        LEDs spread evenly over the rig's 198 (in their order: rings from the top).
    rgb_cameras
        RGB cameras spread evenly over the arc's 11, the top and 75 degree ones included.
    texels
        Texels across a nominal 4 cm sample (:mod:`twin.dome.capture_geometry`).
    spp
        Samples per pixel of the renders.
    led_renders
        ``pose``: the LEDs of a stage position rendered in passes (the default); ``single``:
        one render per LED (:data:`twin.dome.signals.LED_RENDERS`).
    """

    stage_positions: int = 24
    leds: int = 198
    rgb_cameras: int = 11
    texels: int = 64
    spp: int = DEFAULT_SPP
    led_renders: str = "pose"

    def check(self, config: DomeConfig) -> None:
        """Refuse a size the rig cannot take, naming the setting, its range and the value."""
        limits = {
            "stage_positions": config.rotation_stage_positions,
            "leds": config.led_count,
            "rgb_cameras": len(config.rgb_camera_polar_deg),
        }
        for name, top in limits.items():
            value = getattr(self, name)
            if not is_whole(value) or not 1 <= value <= top:
                raise InputError(f"{name}: expected 1..{top} (the rig's), got {value}")
        if not is_whole(self.spp) or self.spp < 1:
            raise InputError(f"spp: expected at least 1 sample per pixel, got {self.spp}")
        if self.led_renders not in LED_RENDERS:
            raise InputError(
                f"led_renders: expected one of {', '.join(LED_RENDERS)}, got {self.led_renders!r}"
            )
        FrameSize(config, self.texels)

    def stage_views(self) -> list[int]:
        return list(range(self.stage_positions))

    def led_ids(self, config: DomeConfig) -> list[int]:
        return _spread(self.leds, config.led_count)

    def camera_ids(self, config: DomeConfig) -> DomeCameraIds:
        arc = _spread(self.rgb_cameras, len(config.rgb_camera_polar_deg))
        return DomeCameraIds(tuple(rgb_camera_id(index) for index in arc), SPECTRAL_CAMERA)


def calibration_led(config: DomeConfig) -> int:
    """The LED nearest the calibration light of :mod:`twin.dome.setup` (15 degrees from the top)."""
    return int(np.argmax(dome_geometry(config).led_directions @ CALIBRATION_LIGHT))


def dome_timing(config: DomeConfig, camera_ids: DomeCameraIds) -> DomeTiming:
    """The rig's timing (``scenes/rigs/dome.yaml``) for the cameras of a plan."""
    timing = config.timing
    overheads = {camera: timing.rgb_frame_overhead_s for camera in camera_ids.rgb}
    overheads[camera_ids.spectral] = timing.spectral_frame_overhead_s
    return DomeTiming(timing.rotation_s, timing.led_switch_s, overheads)


@dataclass(frozen=True)
class DomePlanParts:
    """What the plans of one capture size are made of."""

    cameras: DomeCameraIds
    exposures: DomeExposures
    stage_views: list[int]
    leds: list[int]
    calibration_led: int
    geometric_views: list[tuple[int, float]]


def dome_plan_parts(
    config: DomeConfig,
    size: DomeCaptureSize,
    *,
    longest_band_s: float = THESIS_LONGEST_BAND_S,
    schedule_images: int | None = None,
) -> DomePlanParts:
    """Cameras, exposures, stage positions and LEDs of a capture of ``size``; the spectral
    camera's weakest band exposed ``longest_band_s`` (which sets :math:`t_{base}`, thesis 10.4)
    and the bands packed into ``schedule_images`` RGB images (:func:`twin.dome.exposure_plan
    .dome_exposures`)."""
    if not longest_band_s > 0:
        raise InputError(f"longest_band_s: expected a positive exposure in s, got {longest_band_s}")
    if schedule_images is not None and (not is_whole(schedule_images) or schedule_images < 1):
        raise InputError(f"schedule_images: expected at least 1 RGB image, got {schedule_images}")
    size.check(config)
    cameras = size.camera_ids(config)
    led = calibration_led(config)
    positions = config.rotation_stage_positions
    geometric = [(round(turn * positions) % positions, tilt) for turn, tilt in GEOMETRIC_VIEWS]
    return DomePlanParts(
        cameras,
        dome_exposures(
            config,
            cameras,
            longest_band_s=longest_band_s,
            calibration_led=led,
            schedule_images=schedule_images,
        ),
        size.stage_views(),
        size.led_ids(config),
        led,
        geometric,
    )


def run_plan(parts: DomePlanParts) -> list[dict]:
    """The ``dome-run`` plan of ``parts`` (:func:`hwbridge.dome_plans.dome_run`)."""
    return dome_run(
        parts.cameras, parts.exposures, stage_positions=parts.stage_views, leds=parts.leds
    )


def calibration_plan(parts: DomePlanParts, dark_frames: int) -> list[dict]:
    """The ``dome-calibration`` plan of ``parts`` (:func:`hwbridge.dome_plans.dome_calibration`):
    ``dark_frames`` per spectral exposure time, as many (at most 16) per RGB exposure time."""
    return dome_calibration(
        parts.cameras,
        parts.exposures,
        leds=parts.leds,
        calibration_led=parts.calibration_led,
        geometric_views=parts.geometric_views,
        dark_frames=dark_frames,
        rgb_dark_frames=min(dark_frames, RGB_DARK_FRAMES),
    )


def _spectrum(values: np.ndarray) -> Spectrum:
    return Spectrum(wavelengths_nm=CERTIFICATE_GRID.wavelengths_nm.tolist(), values=values.tolist())


@dataclass(frozen=True, eq=False)
class DomeCaptureProgram(ProgramCapture):
    """A capture program of the simulated dome, checked and ready to run.

    Attributes
    ----------
    name
        ``dome-calibration`` or ``dome-run`` (the ``program`` of the store's rig).
    plan
        One dict per step (:mod:`hwbridge.dome_plans`).
    devices
        The devices' recipe (it pickles, for the workers of a cluster).
    rig
        The store's ``rig`` attribute.
    seed
        The session seed.
    timing
        The rig's timing, for the duration of :meth:`dry_run`.
    scene
        What the cameras render (the passes of :meth:`dry_run`'s render count).
    """

    name: str
    plan: list[dict]
    devices: SimDomeDevices
    rig: DomeRigAttrs
    seed: int
    timing: DomeTiming
    scene: DomeScene

    def _render(self, step: dict, order: dict[int, int], per_pass: dict[str, int]) -> tuple:
        """What one render (or pass of LEDs, :mod:`twin.dome.signals`) of ``step`` shows;
        ``order`` numbers the LEDs lit one at a time in plan order, ``per_pass`` gives each
        camera's LEDs per pass (a pass counted down from below :data:`ALL_LEDS`)."""
        light = step.get("light_id", NO_LIGHT)
        if self.rig.led_renders == "pose" and light >= 0:
            light = ALL_LEDS - 1 - order[light] // per_pass[step["camera"]]
        return step["camera"], step.get("view_id"), light, step["kind"]

    def dry_run(self) -> dict[str, Any]:
        """The plan in numbers, capturing nothing: steps, frames per camera and kind, stage
        positions, LEDs, renders, frame size, the estimated duration (cameras in parallel,
        :func:`hwbridge.dome_plans.dome_duration_s`) and the storage of the frames and their
        index uncompressed."""
        frames = Counter(step["camera"] for step in self.plan)
        side = self.rig.window_px
        order = {led: index for index, led in enumerate(self.scene.single_leds)}
        per_pass = {
            camera: leds_per_pass(side, self.scene.pass_channels(camera_arc_index(camera)))
            for camera in frames
        }
        renders = {
            self._render(step, order, per_pass) for step in self.plan if step["kind"] != "dark"
        }
        duration_s = dome_duration_s(self.plan, self.timing)
        # frame, then light_id, view_id, band_nm (4 bytes each), exposure_s, timestamp (8 each),
        # pose (6 x 8) and the progress flag
        per_frame = 2 * side * side + 3 * 4 + 2 * 8 + 6 * 8 + 1
        return {
            "program": self.name,
            "steps": len(self.plan),
            "frames": dict(frames),
            "kinds": dict(Counter(step["kind"] for step in self.plan)),
            "stage_positions": len({s.get("view_id", NO_VIEW) for s in self.plan} - {NO_VIEW}),
            "leds": len({s.get("light_id", NO_LIGHT) for s in self.plan} - {NO_LIGHT, ALL_LEDS}),
            "renders": len(renders),
            "led_renders": self.rig.led_renders,
            "frame_size": f"{side} x {side} px",
            "spp": self.rig.spp,
            "estimated_duration_s": duration_s,
            "estimated_duration_h": duration_s / 3600,
            "storage_mb": len(self.plan) * per_frame / 1e6,
        }


def _led_bands(plan: list[dict], bands_nm) -> dict[int, tuple[int, ...]]:
    """Per LED lit alone, the spectral camera's bands (indices into ``bands_nm``) the plan takes
    under it (:attr:`twin.dome.signals.DomeScene.led_bands`)."""
    bands: dict[int, set[int]] = {}
    for step in plan:
        if step["camera"] == SPECTRAL_CAMERA and step.get("light_id", NO_LIGHT) >= 0:
            band = band_index(bands_nm, step["band_nm"])
            bands.setdefault(int(step["light_id"]), set()).add(band)
    return {led: tuple(sorted(chosen)) for led, chosen in bands.items()}


def _program(
    name: str,
    config: DomeConfig,
    parts: DomePlanParts,
    plan: list[dict],
    size: DomeCaptureSize,
    *,
    material: str | None,
    seed: int,
    fault_rate: float,
    stage_positions: int | None = None,
    dark_frames: int | None = None,
) -> DomeCaptureProgram:
    """The program of ``plan``: its devices, rendered scene and store metadata (a run's
    ``material`` and ``stage_positions``, a calibration's ``dark_frames``)."""
    frame = FrameSize(config, size.texels)
    sample = load_material(material) if material is not None else None
    exposures = parts.exposures
    scene = DomeScene(
        config,
        sample,
        tuple(holder_content(step["kind"], step.get("tilt_deg")) for step in plan),
        LED_FULL_SCALE_MA,
        frame.pixels,
        frame.window,
        size.spp,
        exposures.bands_nm,
        size.led_renders,
        tuple(
            dict.fromkeys(step["light_id"] for step in plan if step.get("light_id", NO_LIGHT) >= 0)
        ),
        _led_bands(plan, exposures.bands_nm),
    )
    roi = (frame.window, frame.window)
    cameras = []
    for camera in parts.cameras.all:
        arc = camera_arc_index(camera)
        definition = (
            config.spectral_camera.definition if arc == SPECTRAL_CAMERA else config.rgb_camera
        )
        cameras.append((camera, Sensor(definition, roi=roi), RenderedDomeSignal(scene, arc)))
    timing = dome_timing(config, parts.cameras)
    check_exposures(plan, {camera: sensor for camera, sensor, _ in cameras})
    calibration = dark_frames is not None
    devices = SimDomeDevices(
        tuple(cameras),
        dome_start_times_s(plan, timing),
        config.rotation_stage_step_deg,
        config.led_count,
        LED_FULL_SCALE_MA,
        fault_rate=float(fault_rate),
        fault_seed=seed,
        spectrometer=(
            DomeSpectrometer.of_dome(dome_geometry(config).led_positions_m, LED_FULL_SCALE_MA)
            if calibration
            else None
        ),
    )
    views = sorted({step["view_id"] for step in plan if step.get("view_id", NO_VIEW) >= 0})
    tilts = sorted({step["tilt_deg"] for step in plan if "tilt_deg" in step})
    rig = DomeRigAttrs(
        rig="dome",
        program=name,
        material=material,
        sample_size_m=None if sample is None else sample.size_m,
        stage_positions=stage_positions,
        dark_frames=dark_frames,
        texels=size.texels,
        spp=size.spp,
        led_renders=size.led_renders,
        pixels=frame.pixels,
        window_px=frame.window,
        leds=size.leds,
        rgb_cameras=size.rgb_cameras,
        rgb_exposures_s=exposures.rgb_hdr_s,
        bands_nm=exposures.bands_nm,
        band_exposures_s=exposures.band_s,
        band_schedule=exposures.schedule,
        calibration_led=parts.calibration_led,
        led_current_ma=LED_FULL_SCALE_MA,
        white_reflectance=_spectrum(zenith_white_reflectance(CERTIFICATE_GRID).values),
        charts=chart_geometry(CERTIFICATE_GRID) if calibration else None,
        spectrometer_wavelengths_nm=(
            SPECTROMETER_GRID.wavelengths_nm.tolist() if calibration else None
        ),
        geometry=geometry_metadata(
            config, parts.cameras.all, frame, stage_views=views, tilts_deg=tilts
        ),
    )
    return DomeCaptureProgram(name, plan, devices, rig, seed, timing, scene)


def dome_run_program(
    material: str = "colorchecker16",
    *,
    size: DomeCaptureSize = DomeCaptureSize(),
    seed: int = 0,
    fault_rate: float = 0.0,
    config: DomeConfig | None = None,
    longest_band_s: float = THESIS_LONGEST_BAND_S,
    schedule_images: int | None = None,
) -> DomeCaptureProgram:
    """The measurement of ``material`` (``scenes/materials``) at ``size``, checked and not yet
    captured (module docstring); ``fault_rate`` injects device faults drawn from ``seed``.
    ``config`` is the rig model (default ``scenes/rigs/dome.yaml``), ``longest_band_s`` and
    ``schedule_images`` set the band exposures and their schedule (:func:`dome_plan_parts`)."""
    check_seed(seed)
    check_fault_rate(fault_rate)
    if material not in available_materials():
        raise InputError(f"material: expected one of {available_materials()}, got {material!r}")
    config = config or load_rig("dome")
    parts = dome_plan_parts(
        config, size, longest_band_s=longest_band_s, schedule_images=schedule_images
    )
    plan = run_plan(parts)
    return _program(
        "dome-run",
        config,
        parts,
        plan,
        size,
        material=material,
        seed=seed,
        fault_rate=fault_rate,
        stage_positions=size.stage_positions,
    )


def dome_calibration_program(
    *,
    size: DomeCaptureSize = DomeCaptureSize(),
    dark_frames: int = 200,
    seed: int = 0,
    fault_rate: float = 0.0,
    config: DomeConfig | None = None,
    longest_band_s: float = THESIS_LONGEST_BAND_S,
    schedule_images: int | None = None,
) -> DomeCaptureProgram:
    """The calibration at ``size`` (its LEDs and cameras are the run's), ``dark_frames`` per
    spectral exposure time (thesis 10.3: 200; the RGB cameras take as many, at most 16, per
    exposure time), checked and not yet captured. ``size.stage_positions`` is not used: the
    geometric frames take the stage positions of :data:`GEOMETRIC_VIEWS`. ``config``,
    ``longest_band_s`` and ``schedule_images`` as for :func:`dome_run_program` (the dark frames
    span the run's band exposures)."""
    check_seed(seed)
    check_fault_rate(fault_rate)
    if not is_whole(dark_frames) or dark_frames < 1:
        raise InputError(f"dark_frames: expected at least 1, got {dark_frames}")
    config = config or load_rig("dome")
    parts = dome_plan_parts(
        config, size, longest_band_s=longest_band_s, schedule_images=schedule_images
    )
    plan = calibration_plan(parts, dark_frames)
    return _program(
        "dome-calibration",
        config,
        parts,
        plan,
        size,
        material=None,
        seed=seed,
        fault_rate=fault_rate,
        dark_frames=dark_frames,
    )


def stored_dome_settings(store: CaptureStore) -> dict[str, Any]:
    """The program and settings a dome store was made with, as ``spectwin capture`` names them:
    ``program``, ``seed``, ``stage_positions``, ``leds``, ``rgb_cameras``, ``texels``, ``spp``,
    ``led_renders`` and ``material`` (run) or ``dark_frames`` (calibration)."""
    rig = store.rig_attrs(DomeRigAttrs)
    settings = {"program": rig.program, "seed": store.metadata.seed}
    names = (
        "stage_positions",
        "leds",
        "rgb_cameras",
        "texels",
        "spp",
        "led_renders",
        "material",
        "dark_frames",
    )
    recorded = {name: getattr(rig, name) for name in names}
    return settings | {name: value for name, value in recorded.items() if value is not None}
