"""Capture programs of the simulated gonioreflectometer (thesis 3.3 and 4.1.1).

Two sessions, as on the real rig:

1. ``calibration``: the Zenith white standard on the sample holder facing the HMI lamp; dark
   frames, an exposure series at 550 nm for the response curve (Robertson), and one photograph
   per VariSpec band at one exposure time, for the factors :math:`F_\\lambda` of Eq. 3.3 and the
   exposure plan of Eq. 3.4 (``spectwin calibrate``).
2. ``run``: one measurement run with the planned band exposures: dark frames spanning them, the
   white standard through every band (:math:`F'_\\lambda` of the run, Eq. 3.6), then per
   direction pair the material on its holder through every band. The lamp monitor records the
   lamp with every lit frame (:math:`F_{i,long}`).

The material is rendered by Mitsuba for the pose the robot actually reaches
(:func:`actual_poses`: the nominal pose off by the robot's repeatability), so every frame needs
registration. The store's ``rig`` attribute carries what real processing knows about the rig:
the nominal directions, the approximate image corners of the registration marks from the nominal
kinematics, the sample's size relative to the marks and the white standard's certified
reflectance, and the program's settings (``program``, ``material``, ``sensor_px``,
``window_px``, ``spp``), which a resumed capture reads back (:func:`stored_settings`); its
``config``, the rig model, is for the twin's evaluation (processing never reads it). Exposure
times are multiples of 1/15 s (HMI flicker, thesis 3.2.2).

Each program is first built as a :class:`CaptureProgram` (:func:`gonio_calibration_program`,
:func:`gonio_measurement_program`): building checks every setting against the rig and camera
models and writes nothing, so settings that cannot work are refused before a store exists;
:meth:`CaptureProgram.dry_run` describes the plan (steps, frames, duration, storage) and
:meth:`CaptureProgram.run` captures it.
"""

from __future__ import annotations

from collections import Counter
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np

from hwbridge.plans import (
    dark_series,
    gonio_sample_run,
    plan_start_times_s,
    response_curve_series,
    white_reference_run,
)
from hwbridge.schema import NO_VIEW, GonioRigAttrs, Spectrum, recorded
from hwbridge.store import CaptureStore
from recon.calibration.spectral import HMI_FLICKER_PERIOD_S
from recon.errors import InputError
from recon.registration.corners import CORNER_PIECE_SIZE
from recon.spectra import DEFAULT_GRID
from twin.components.lctf import LiquidCrystalTunableFilter
from twin.components.targets import zenith_white_reflectance
from twin.devices.programs import (
    ProgramCapture,
    check_exposures,
    check_fault_rate,
    check_seed,
    is_whole,
)
from twin.devices.sim_devices import SimGonioDevices, VirtualRig
from twin.gonio.capture_time import estimate_plan_s
from twin.gonio.mark_width import RegistrationOutlook, registration_outlook
from twin.gonio.render import GONIO_SPP, gonio_camera, gonio_lamp, pose_matrix
from twin.gonio.signals import RenderedGonioSignal, WhiteReferenceSignal
from twin.materials import load_material
from twin.materials.sample_holder import PRINT_OUTER_HALF_M, registration_corners
from twin.render.scene import centred_window_offset
from twin.rigs.gonio_kinematics import GonioPose, perturbed_pose, solve_pairs
from twin.rigs.hemisphere import direction, sattler_directions
from twin.rigs.rig_config import GonioConfig, load_rig
from twin.sensor.model import Sensor

if TYPE_CHECKING:
    from distributed import Client

__all__ = [
    "CAMERA_ID",
    "GLOSSY_RINGS",
    "REDUCED_RINGS",
    "SAMPLINGS",
    "CaptureProgram",
    "GonioPairs",
    "actual_poses",
    "check_capture_settings",
    "gonio_calibration_program",
    "gonio_measurement_program",
    "gonio_pairs",
    "is_flickering",
    "run_gonio_calibration",
    "run_gonio_measurement",
    "stored_settings",
    "texture_corners_world",
]

CAMERA_ID = "k4"
REDUCED_RINGS = ((0.0, 1), (30.0, 4), (60.0, 8))
"""13 directions (rings of polar angle 0, 30, 60 degrees): the reduced sampling of the twin's
end-to-end check, 13 x 13 light x view combinations."""
GLOSSY_RINGS = ((0.0, 1), (15.0, 6), (30.0, 12), (45.0, 18), (60.0, 20))
"""57 directions: Sattler's rings (thesis 3.1) up to 60 degrees polar, 3192 reachable light x
view combinations. The sampling at which Figure 4.6 holds on glossy fields (BENCHMARKS.md,
Figure 4.6); its virtual capture takes about half an hour on 2 cores."""
SAMPLINGS = {"reduced": REDUCED_RINGS, "glossy": GLOSSY_RINGS}
"""The named direction samplings of a measurement run (``spectwin capture --sampling``)."""
_OECF_BANDS_NM = (420.0, 450.0, 550.0, 650.0, 700.0)
_OECF_EXPOSURES = 200  # per band; thesis 3.3: 200 exposures for the response curve
_DARK_FRAMES = 8
# Index bytes per frame besides the lamp monitor: light_id, view_id, band_nm (4 each),
# exposure_s, timestamp (8 each), pose (6 x 8), the progress flag (1).
_INDEX_BYTES = 3 * 4 + 2 * 8 + 6 * 8 + 1


class GonioPairs:
    """The reachable direction pairs of a sampling and their nominal robot poses."""

    def __init__(self, config: GonioConfig, light_dirs: np.ndarray, view_dirs: np.ndarray):
        solution = solve_pairs(config, light_dirs, view_dirs)
        keep = np.flatnonzero(solution.exact)
        if keep.size == 0:
            raise InputError("directions: the rig reaches none of the direction pairs")
        self.light_dirs = np.asarray(light_dirs, np.float64)[keep]
        self.view_dirs = np.asarray(view_dirs, np.float64)[keep]
        self.poses = [pose for i in keep if (pose := solution.poses[i]) is not None]
        self.skipped = int(len(solution.poses) - keep.size)


def gonio_pairs(
    config: GonioConfig, rings: tuple[tuple[float, int], ...] = REDUCED_RINGS
) -> GonioPairs:
    """Every light x view combination of a ring sampling that the rig reaches exactly."""
    directions = sattler_directions(rings)
    return GonioPairs(
        config,
        np.repeat(directions, len(directions), axis=0),
        np.tile(directions, (len(directions), 1)),
    )


def actual_poses(config: GonioConfig, nominal: list[GonioPose], seed: int) -> list[GonioPose]:
    """The poses the robot reaches in session ``seed`` (repeatability, one draw per pair)."""
    return [
        perturbed_pose(pose, config, np.random.default_rng([seed, 7, index]))
        for index, pose in enumerate(nominal)
    ]


def texture_corners_world(pose: GonioPose) -> np.ndarray:
    """World points ``(4, 3)`` of the registration marks' corners in texture order (texture
    ``(0,0), (1,0), (1,1), (0,1)`` = sample ``(-h, +h), (+h, +h), (+h, -h), (-h, -h)``), the
    orientation of the twin's truth textures (:mod:`twin.render.truth`)."""
    return _in_world(registration_corners()[[1, 0, 3, 2]], pose)


def _in_world(points: np.ndarray, pose: GonioPose) -> np.ndarray:
    """Sample-frame ``points`` ``(n, 3)`` in the world, the sample held at ``pose``."""
    matrix = pose_matrix(pose)
    return points @ matrix[:3, :3].T + matrix[:3, 3]


def _marks_window_px(config: GonioConfig, pose: GonioPose, pixels: int) -> int:
    """The smallest centred window (pixels of ``pixels`` across the field) that holds the image
    pieces around the four corners of the holder's marks at ``pose``, in which the
    registration refines them."""
    reach = CORNER_PIECE_SIZE * PRINT_OUTER_HALF_M  # half a piece, in metres
    offsets = np.array([[1, 1, 0], [-1, 1, 0], [-1, -1, 0], [1, -1, 0]]) * reach
    points = (registration_corners()[:, None, :] + offsets).reshape(-1, 3)
    xy = gonio_camera(config, pose.rail_deg, pixels).project(_in_world(points, pose))
    sides = np.arange(1, pixels + 1)
    first = centred_window_offset(pixels, sides)  # the window's first pixel, as cropped
    holds = (first <= xy.min()) & (first + sides >= xy.max())
    return int(sides[holds][0]) if holds.any() else pixels + 1


def _flicker_multiples(times_s: np.ndarray) -> np.ndarray:
    """Times rounded up to whole HMI flicker periods (at least one)."""
    periods = np.maximum(np.ceil(np.asarray(times_s) / HMI_FLICKER_PERIOD_S - 1e-9), 1)
    return np.unique(periods) * HMI_FLICKER_PERIOD_S


def _white_signal(config: GonioConfig, sensor: Sensor) -> WhiteReferenceSignal:
    """The white standard facing the rig's first lamp position, through the rig's filter."""
    lamp, _ = gonio_lamp(config, config.lamps[0].id)
    return WhiteReferenceSignal(
        sensor, lamp, distance_m=config.lamps[0].distance_m, filter_model=config.camera.filter
    )


def is_flickering(config: GonioConfig) -> bool:
    """Whether the rig's lamps flicker (HMI, thesis 3.2.2): exposures must then be whole
    numbers of flicker periods."""
    return any(placement.spectrum == "hmi" for placement in config.lamps)


def _rig_attrs(config: GonioConfig, pixels: int, program: str, **run: Any) -> GonioRigAttrs:
    """The store's ``rig`` attribute of ``program``; a run adds its own fields (``run``)."""
    white = zenith_white_reflectance(DEFAULT_GRID)
    return GonioRigAttrs(
        rig="gonioreflectometer",
        program=program,
        camera=config.camera.definition,
        camera_id=CAMERA_ID,
        window_px=pixels,
        lamp=config.lamps[0].spectrum,
        config=config.model_dump(mode="json"),
        white_reflectance=Spectrum(
            wavelengths_nm=white.wavelengths_nm.tolist(), values=white.values.tolist()
        ),
        **run,
    )


class _GonioSignal:
    """The white standard at view ``white_view``, the rendered material at every other view."""

    def __init__(self, white: WhiteReferenceSignal, white_view: int, material=None):
        self._white, self._white_view, self._material = white, white_view, material

    def __call__(self, rig: VirtualRig, start_s: float, exposure_s: float) -> np.ndarray:
        if rig.view_id == self._white_view:
            return self._white(rig, start_s, exposure_s)
        return self._material(rig, start_s, exposure_s)


def check_capture_settings(
    config: GonioConfig, *, pixels: int, window: int | None = None, spp: int = 1
) -> None:
    """Refuse capture settings that the rig's camera cannot take, before anything is made.

    ``pixels`` across the camera's field are at most the sensor's pixels; the read-out
    ``window`` (a region of interest) lies within them; renders take at least one sample per
    pixel.

    Raises
    ------
    InputError
        Naming the setting, its range and the value given.
    """
    camera = Sensor(config.camera.definition).config
    side = min(camera.width, camera.height)
    if not is_whole(pixels) or not 1 <= pixels <= side:
        raise InputError(
            f"pixels: expected 1..{side} pixels across the field of the {camera.name} (its "
            f"sensor has {camera.width}x{camera.height}), got {pixels}"
        )
    if window is not None and (not is_whole(window) or not 1 <= window <= pixels):
        raise InputError(
            f"window: expected a read-out window of 1..{pixels} pixels (at most pixels, "
            f"{pixels}), got {window}"
        )
    if not is_whole(spp) or spp < 1:
        raise InputError(f"spp: expected at least 1 sample per pixel, got {spp}")


@dataclass(frozen=True, eq=False)
class CaptureProgram(ProgramCapture):
    """A capture program of the simulated gonioreflectometer, checked and ready to run.

    Attributes
    ----------
    name
        ``demo``, ``gonio-calibration`` or ``gonio-run`` (the ``program`` of the store's rig).
    plan
        One dict per step (:mod:`hwbridge.plans`).
    devices
        The devices' recipe (it pickles, for the workers of a cluster).
    rig
        The store's ``rig`` attribute.
    seed
        The session seed.
    poses
        The robot pose of each view that has one (the capture-time estimate).
    config
        The rig model the program was built for (default ``scenes/rigs/gonio.yaml``).
    """

    name: str
    plan: list[dict]
    devices: SimGonioDevices
    rig: GonioRigAttrs
    seed: int
    poses: dict[int, GonioPose]
    config: GonioConfig | None = None

    def __post_init__(self) -> None:
        check_seed(self.seed)
        check_fault_rate(self.devices.fault_rate)
        check_exposures(self.plan, {self.devices.camera_id: self.devices.sensor})

    def dry_run(self) -> dict[str, Any]:
        """The plan in numbers, capturing nothing: steps, frames per camera and per kind,
        views, frame size, samples per pixel of the renders (where it renders), the estimated
        duration (the rig's timing,
        :func:`twin.gonio.capture_time.estimate_plan_s`) and the storage the frames and their
        index take uncompressed (the store compresses them)."""
        devices = self.devices()
        monitor = devices.monitor
        samples = monitor.samples if monitor is not None else 0
        frames = Counter(step["camera"] for step in self.plan)
        storage = 0
        for camera, count in frames.items():
            height, width = devices.cameras[camera].frame_shape
            storage += count * (2 * height * width + _INDEX_BYTES + 4 * samples)
        duration_s = estimate_plan_s(self.config or load_rig("gonio"), self.plan, self.poses)
        height, width = self.devices.sensor.height, self.devices.sensor.width
        return (
            {
                "program": self.name,
                "steps": len(self.plan),
                "frames": dict(frames),
                "kinds": dict(Counter(step["kind"] for step in self.plan)),
                "views": len({step.get("view_id", NO_VIEW) for step in self.plan} - {NO_VIEW}),
                "frame_size": f"{height} x {width} px",
                **({"spp": self.rig.spp} if self.rig.spp is not None else {}),
                "estimated_duration_s": duration_s,
                "estimated_duration_h": duration_s / 3600,
                "storage_mb": storage / 1e6,
            }
            | self.marks_outside_window()
            | self._registration_summary()
        )

    def _registration_summary(self) -> dict[str, object]:
        outlook = self.registration_outlook()
        return {} if outlook is None else outlook.summary()

    def registration_outlook(self) -> RegistrationOutlook | None:
        """For a measurement run: the pairs whose registration marks are predicted too narrow to
        register at the run's pixels across the field, and the pixels that register every
        pair (:func:`twin.gonio.mark_width.registration_outlook`); ``None`` for other
        programs."""
        if self.name != "gonio-run":
            return None
        pixels = int(recorded(self.rig.sensor_px, "rig.sensor_px"))
        config = self.config or load_rig("gonio")
        camera = Sensor(config.camera.definition).config
        return registration_outlook(config, self.poses, pixels, min(camera.width, camera.height))

    def marks_outside_window(self) -> dict[str, int]:
        """For a measurement run: ``pairs_with_marks_outside_window``, the pairs in which the
        window read out cuts into an image piece that the registration refines a corner of the
        holder's marks in (:data:`recon.registration.corners.CORNER_PIECE_SIZE`), so that they
        may not register, and ``window_px_holding_marks``, the smallest centred window that
        holds every pair's pieces; empty for other programs."""
        if self.name != "gonio-run":
            return {}
        pixels = int(recorded(self.rig.sensor_px, "rig.sensor_px"))
        config = self.config or load_rig("gonio")
        needed = np.array([_marks_window_px(config, pose, pixels) for pose in self.poses.values()])
        return {
            "pairs_with_marks_outside_window": int((needed > self.devices.sensor.width).sum()),
            "window_px_holding_marks": int(needed.max()),
        }


def stored_settings(store: CaptureStore) -> dict[str, Any]:
    """The program and settings a capture store was made with, as ``spectwin capture`` names
    them: ``program``, ``seed`` and, for a measurement run, ``material``, ``pixels``,
    ``window`` (``None`` when the whole field is read out), ``spp`` and the band
    ``exposures_s`` of its white frames."""
    attrs = store.metadata
    if attrs.backend != "sim":
        raise InputError(
            f"{store.path}: a {attrs.backend!r} store, not made by spectwin capture; only "
            "simulated captures continue where they stopped"
        )
    rig = store.rig_attrs(GonioRigAttrs)
    settings: dict[str, Any] = {"program": rig.program, "seed": attrs.seed}
    if rig.program == "gonio-run":
        pixels = int(recorded(rig.sensor_px, f"{store.path}: rig.sensor_px"))
        settings |= {
            "material": rig.material,
            "pixels": pixels,
            "window": None if rig.window_px == pixels else rig.window_px,
            "spp": rig.spp,
            "sampling": _sampling_name(rig.rings),
            "exposures_s": np.array(
                [step.exposure_s for step in attrs.plan if step.kind == "white"]
            ),
        }
    return settings


def _sampling_name(rings: tuple[tuple[float, int], ...] | None) -> str | None:
    """The name in :data:`SAMPLINGS` of a store's rings (``None``: explicit pairs)."""
    if rings is None:
        return None
    return next((name for name, value in SAMPLINGS.items() if value == rings), None)


def _with_view(steps: list[dict], view: int) -> list[dict]:
    return [{**step, "view_id": view} for step in steps]


def gonio_calibration_program(
    *,
    pixels: int = 64,
    spp: int = GONIO_SPP,
    seed: int = 0,
    white_fill: float = 0.6,
    config: GonioConfig | None = None,
) -> CaptureProgram:
    """The calibration session (see the module docstring), checked and not yet captured.

    The response series photographs the colour checker on its holder (view 1, seen frontally,
    lit from 30 degrees: its fields, card and print give the spread of radiances Robertson's
    method needs, a uniform target gives one value per exposure) at 1/15 s to 20 s in
    five bands (420-700 nm: five scenes for Robertson's method, the weak blue band fills the low
    levels),
    about 150 distinct whole numbers of flicker periods (thesis 3.3: 200 exposures). The white
    photographs (view 0) share one exposure time, the longest whole number of flicker periods
    that keeps the brightest band below ``white_fill`` of saturation (the operator's test shots).
    ``config`` is the rig model (default ``scenes/rigs/gonio.yaml``): its first lamp position
    lights the white standard, through its filter. Whole flicker periods suit a steady QTH lamp
    as well.
    """
    config = config or load_rig("gonio")
    check_capture_settings(config, pixels=pixels, spp=spp)
    check_seed(seed)
    if not 0.0 < white_fill < 1.0:
        raise InputError(
            f"white_fill: expected a fraction of saturation in (0, 1), got {white_fill}"
        )
    sensor = Sensor(config.camera.definition, roi=(pixels, pixels))
    lctf = LiquidCrystalTunableFilter.varispec(config.camera.filter)
    white = _white_signal(config, sensor)
    bands = np.asarray(lctf.band_centres_nm, np.float64)
    saturation_s = sensor.saturation_capacity_e / white.rates_e_per_s()
    white_s = max(np.floor(white_fill * saturation_s.min() / HMI_FLICKER_PERIOD_S), 1)
    white_s *= HMI_FLICKER_PERIOD_S
    oecf_s = _flicker_multiples(np.geomspace(HMI_FLICKER_PERIOD_S, 20.0, _OECF_EXPOSURES))
    plan = dark_series(CAMERA_ID, [white_s], _DARK_FRAMES)
    oecf = response_curve_series(CAMERA_ID, oecf_s)
    for band in _OECF_BANDS_NM:
        plan += _with_view([{**step, "band_nm": band} for step in oecf], 1)
    plan += _with_view(white_reference_run(CAMERA_ID, bands, np.full(bands.size, white_s)), 0)
    (chart_pose,) = GonioPairs(config, direction(30.0, 0.0)[None], direction(0.0, 0.0)[None]).poses
    chart = RenderedGonioSignal(
        config, load_material("colorchecker16"), {1: chart_pose}, pixels=pixels, spp=spp
    )
    devices = SimGonioDevices(
        CAMERA_ID, sensor, _GonioSignal(white, 0, chart), plan_start_times_s(plan), 2
    )
    attrs = _rig_attrs(config, pixels, "gonio-calibration")
    return CaptureProgram("gonio-calibration", plan, devices, attrs, seed, {1: chart_pose}, config)


def run_gonio_calibration(
    store: str | Path,
    *,
    pixels: int = 64,
    spp: int = GONIO_SPP,
    seed: int = 0,
    white_fill: float = 0.6,
    config: GonioConfig | None = None,
    resume: bool = False,
    show_progress: bool = False,
    client: Client | None = None,
) -> CaptureStore:
    """The calibration session (:func:`gonio_calibration_program`) into ``store``. With a Dask
    ``client`` the session runs over its cluster (:mod:`twin.devices.cluster`)."""
    program = gonio_calibration_program(
        pixels=pixels, spp=spp, seed=seed, white_fill=white_fill, config=config
    )
    return program.run(store, resume=resume, show_progress=show_progress, client=client)


def gonio_measurement_program(
    exposures_s: np.ndarray,
    *,
    material: str = "colorchecker16",
    rings: tuple[tuple[float, int], ...] = REDUCED_RINGS,
    pairs: GonioPairs | None = None,
    pixels: int = 256,
    window: int | None = None,
    spp: int = GONIO_SPP,
    seed: int = 0,
    config: GonioConfig | None = None,
) -> CaptureProgram:
    """One measurement run (see the module docstring), checked and not yet captured.

    Parameters
    ----------
    exposures_s
        ``(33,)`` band exposure times from the calibration (Eq. 3.4), multiples of 1/15 s.
    material
        Material on the holder (``scenes/materials``).
    rings, pairs
        The direction sampling: every reachable light x view combination of ``rings``, or the
        given pairs.
    pixels, window, spp
        Pixels per side over the camera's 20 cm field, the centred window of them read out
        (default all; the K4's region of interest) and samples per pixel
        (:func:`check_capture_settings`).
    seed
        Session seed (noise, robot repeatability).
    config
        The rig model (default ``scenes/rigs/gonio.yaml``): lamps, filter, camera, kinematics.
    """
    config = config or load_rig("gonio")
    check_capture_settings(config, pixels=pixels, window=window, spp=spp)
    check_seed(seed)
    lctf = LiquidCrystalTunableFilter.varispec(config.camera.filter)
    bands = np.asarray(lctf.band_centres_nm, np.float64)
    exposures = np.asarray(exposures_s, np.float64)
    if exposures.shape != bands.shape or not np.all(np.isfinite(exposures) & (exposures > 0)):
        raise InputError(
            f"exposures_s: expected {bands.size} positive band exposure times, got "
            f"shape {exposures.shape}"
        )
    periods = exposures / HMI_FLICKER_PERIOD_S
    if is_flickering(config) and not np.allclose(periods, np.round(periods), rtol=0, atol=1e-6):
        raise InputError(
            "exposures_s: with the HMI lamp every band exposure must be a multiple of 1/15 s "
            "(thesis 3.2.2); plan them with spectwin calibrate"
        )
    sample = load_material(material)
    stored_rings = None if pairs is not None else [list(ring) for ring in rings]
    pairs = pairs or gonio_pairs(config, rings)
    n_pairs = len(pairs.poses)
    side = window or pixels
    sensor = Sensor(config.camera.definition, roi=(side, side))
    dark_s = np.linspace(exposures.min(), exposures.max(), 4)
    dark_s = _flicker_multiples(dark_s) if is_flickering(config) else np.unique(dark_s)
    plan = dark_series(CAMERA_ID, dark_s, _DARK_FRAMES)
    plan += _with_view(white_reference_run(CAMERA_ID, bands, exposures), n_pairs)
    plan += gonio_sample_run(CAMERA_ID, range(n_pairs), bands, exposures)
    rendered = RenderedGonioSignal(
        config,
        sample,
        actual_poses(config, pairs.poses, seed),
        pixels=pixels,
        spp=spp,
        window=window,
    )
    signal = _GonioSignal(_white_signal(config, sensor), n_pairs, rendered)
    expected = np.stack(
        [
            gonio_camera(config, pose.rail_deg, pixels, window).project(texture_corners_world(pose))
            for pose in pairs.poses
        ]
    )
    attrs = _rig_attrs(
        config,
        side,
        "gonio-run",
        sensor_px=pixels,
        material=material,
        spp=spp,
        rings=stored_rings,
        white_view_id=n_pairs,
        light_dirs=pairs.light_dirs.tolist(),
        view_dirs=pairs.view_dirs.tolist(),
        skipped_pairs=pairs.skipped,
        expected_corners_xy=expected.tolist(),
        sample_fraction=sample.size_m / (2 * PRINT_OUTER_HALF_M),
    )
    devices = SimGonioDevices(CAMERA_ID, sensor, signal, plan_start_times_s(plan), n_pairs + 1)
    return CaptureProgram(
        "gonio-run", plan, devices, attrs, seed, dict(enumerate(pairs.poses)), config
    )


def run_gonio_measurement(
    store: str | Path,
    exposures_s: np.ndarray,
    *,
    material: str = "colorchecker16",
    rings: tuple[tuple[float, int], ...] = REDUCED_RINGS,
    pairs: GonioPairs | None = None,
    pixels: int = 256,
    window: int | None = None,
    spp: int = GONIO_SPP,
    seed: int = 0,
    config: GonioConfig | None = None,
    resume: bool = False,
    show_progress: bool = False,
    client: Client | None = None,
) -> CaptureStore:
    """One measurement run (:func:`gonio_measurement_program`, whose parameters these are)
    into ``store``; ``resume`` continues an interrupted run, ``client`` (a Dask client) captures
    over its cluster (:mod:`twin.devices.cluster`), ``None`` in this process: the frames are the
    same."""
    program = gonio_measurement_program(
        exposures_s,
        material=material,
        rings=rings,
        pairs=pairs,
        pixels=pixels,
        window=window,
        spp=spp,
        seed=seed,
        config=config,
    )
    return program.run(store, resume=resume, show_progress=show_progress, client=client)
