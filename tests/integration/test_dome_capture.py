"""Rendered dome captures into capture stores (thesis 10.2-10.4): the renders against the closed
form of a diffuse flat field, the stores' frames, index and geometry, the holder's marks found
where the metadata says, the checkerboard frames calibrating the cameras with OpenCV.

The captures here are small (one or two LEDs, one RGB camera and the spectral camera, 32 or 48
texels) so that the tests take seconds; the reduced capture of 2 stage positions x 24 LEDs x 3
RGB cameras at 64 texels is timed by ``benchmarks/dome_capture.py``.
"""

from __future__ import annotations

import math

import cv2
import numpy as np
import pytest

from hwbridge.dome_layout import ALL_LEDS, SPECTRAL_CAMERA, camera_steps
from hwbridge.schema import PlanStep
from hwbridge.session import SessionSettings, capture_steps, locked_session_store
from hwbridge.store import CaptureStore
from recon.radiometric.demosaic import bin_quads, demosaic
from recon.registration.border import register_frame
from twin.dome.capture import THESIS_BANDS_NM, dome_cameras
from twin.dome.holder import holder_scene_parts
from twin.dome.programs import DomeCaptureSize, dome_calibration_program, dome_run_program
from twin.dome.render import dome_part_rates
from twin.rigs.dome_geometry import dome_geometry
from twin.rigs.rig_config import load_rig

pytestmark = pytest.mark.render

SEED = 2026
# The runs at 4 samples per pixel (the fewest rendered), a quarter of the default's render time:
# the holder's marks and the material's frames need no more. The calibration keeps the default
# 16: at 4 the flat board seen head-on by the top camera puts cv2.solvePnP's camera 2.6 % of
# its distance away (1.5 % at 16), past the 2 % bound.
RUN_SIZE = DomeCaptureSize(stage_positions=2, leds=1, rgb_cameras=1, texels=32, spp=4)
CALIBRATION_SIZE = DomeCaptureSize(leds=1, rgb_cameras=1, texels=48)


@pytest.mark.parametrize("camera", [6, SPECTRAL_CAMERA])
def test_a_white_flat_field_renders_as_rho_i_cos_over_pi_r2(camera):
    """The white standard on the holder, one LED on, rendered at the default spp, against the
    analytic path of the thesis's simulation (``twin.dome.capture``: radiance rho I cos /
    (pi r^2) through the camera model), per RGB channel and per band. Tolerance 0.5 %: the node
    transport leaves no spectral sampling noise (measured: patch means within 0.02 % of the
    closed form in every channel and band; Mitsuba's spectral path tracer at 64 spp left up to
    0.9 % and needed 1.5 %); over the +-2.5 mm patch the LED's distance and angle change by at
    most 0.3 %, linearly, so it cancels in the patch mean, and the pixels differ by that
    gradient alone (measured 0.33 % median standard deviation per channel)."""
    config = load_rig("dome")
    led = 60  # the second ring, 17 degrees from the top
    cos_i = dome_geometry(config).led_directions[led, 2]
    rates = dome_part_rates(
        config,
        holder_scene_parts("white", None),
        stage_deg=15.0,
        leds=[led],
        camera=camera,
        pixels=320,
        window=64,
        bands_nm=THESIS_BANDS_NM,
    )
    rgb_white, band_white = dome_cameras(1, texel_px=2).white_rates()
    expected = cos_i * (band_white if camera == SPECTRAL_CAMERA else rgb_white)
    patch = rates[28:36, 28:36].reshape(-1, rates.shape[-1])
    relative = patch.mean(axis=0) / expected - 1
    assert np.abs(relative).max() < 0.005, relative
    assert np.median(patch.std(axis=0) / patch.mean(axis=0)) < 0.005


@pytest.fixture(scope="module")
def calibration(tmp_path_factory) -> CaptureStore:
    """Part of a calibration capture: the steps of the spectral camera's white frames under the
    calibration LED in the 550 nm band and its dark frames at that exposure, and every
    geometric frame of the top RGB camera and the spectral camera (the rest stays pending)."""
    program = dome_calibration_program(size=CALIBRATION_SIZE, dark_frames=3, seed=SEED)
    plan, rig = program.plan, program.rig
    reference_s = rig.band_exposures_s[rig.bands_nm.index(550.0)]
    steps = [
        step
        for step, settings in enumerate(plan)
        if settings["kind"] == "geometric"
        or (
            settings["camera"] == SPECTRAL_CAMERA
            and settings["exposure_s"] == reference_s
            and (
                settings["kind"] == "dark"
                or (settings["kind"] == "white" and settings["light_id"] == rig.calibration_led)
            )
        )
    ]
    path = tmp_path_factory.mktemp("dome") / "calibration.capture.zarr"
    settings = SessionSettings(rig=rig, backend="sim", seed=SEED)
    with locked_session_store(path, plan, program.devices(), settings) as store:
        capture_steps(store, steps, program.devices(SEED, steps))
    store = CaptureStore.open(path)
    assert sorted(set(range(len(plan))) - set(store.pending_steps())) == steps
    return store


def _frames(store: CaptureStore, camera: str, **wanted) -> tuple[np.ndarray, list[PlanStep]]:
    """The frames of ``camera`` whose plan steps have the ``wanted`` settings, and the steps."""
    plan = store.metadata.plan
    slots = [
        slot
        for slot, step in enumerate(camera_steps(plan, camera))
        if all(getattr(plan[step], key) == value for key, value in wanted.items())
    ]
    steps = [plan[camera_steps(plan, camera)[slot]] for slot in slots]
    return store.read_frames(camera, slots).astype(np.float64), steps


def test_stored_white_frames_carry_the_closed_form_signal(calibration):
    """The spectral camera's white frames in the store (rendered, then the sensor model) minus
    the mean of its dark frames at the same exposure: the K4 is linear, so the patch mean is
    gain x (rho I cos / (pi r^2) through the 550 nm band) x t, within 2 % (shot noise over the
    patch 0.4 %, dark frames averaged, the renders' 0.5 % above)."""
    rig = calibration.attrs["rig"]
    config = load_rig("dome")
    led = rig["calibration_led"]
    cos_i = dome_geometry(config).led_directions[led, 2]
    _, band_white = dome_cameras(1, texel_px=2).white_rates()
    band = list(THESIS_BANDS_NM).index(550.0)
    frames, steps = _frames(calibration, SPECTRAL_CAMERA, kind="white", band_nm=550.0, light_id=led)
    exposure = steps[0].exposure_s
    darks, _ = _frames(calibration, SPECTRAL_CAMERA, kind="dark", exposure_s=exposure)
    assert len(darks) == 3
    signal = frames[0] - darks.mean(axis=0)
    centre = rig["window_px"] // 2
    patch = signal[centre - 8 : centre + 8, centre - 8 : centre + 8].mean()
    gain = 0.2  # scenes/cameras/coolsnap_k4.yaml
    expected = gain * cos_i * band_white[band] * exposure
    assert patch == pytest.approx(expected, rel=0.02)


def _board_corners(store: CaptureStore, camera: str):
    """Checkerboard corners ``(n, 2)`` found by OpenCV in each geometric frame of ``camera``
    (full resolution: RGB frames demosaiced), with the frames' plan steps."""
    target = store.attrs["rig"]["geometry"]["geometric_target"]
    frames, steps = _frames(store, camera, kind="geometric")
    found = []
    for frame, step in zip(frames, steps, strict=True):
        image = frame if camera == SPECTRAL_CAMERA else demosaic(frame).mean(axis=-1)
        image = cv2.normalize(image, None, 0, 255, cv2.NORM_MINMAX).astype(np.uint8)
        pattern = tuple(target["inner_corners"])
        ok, corners = cv2.findChessboardCornersSB(image, pattern, flags=cv2.CALIB_CB_EXHAUSTIVE)
        if ok:
            found.append((corners.reshape(-1, 2).astype(np.float64), step))
    return found, frames.shape[1:]


def _target_to_world(geometry: dict, step: PlanStep) -> np.ndarray:
    """4x4 pose of the checkerboard of a geometric frame in the world: on its wedge
    (``target_to_sample``), turned by the stage."""
    pose = np.asarray(geometry["geometric_target"]["target_to_sample"][f"{step.tilt_deg:g}"])
    turn = np.radians(geometry["stage_angles_deg"][step.view_id])
    stage = np.eye(4)
    stage[:2, :2] = [[math.cos(turn), -math.sin(turn)], [math.sin(turn), math.cos(turn)]]
    return stage @ pose


def _moved(pose: np.ndarray, points: np.ndarray) -> np.ndarray:
    return np.asarray(points) @ pose[:3, :3].T + pose[:3, 3]


@pytest.mark.parametrize("camera", ["rgb00", SPECTRAL_CAMERA])
def test_checkerboard_frames_give_the_cameras_geometry_to_opencv(calibration, camera):
    """The checkerboard, flat and on its 30 degree wedge at eight stage angles, found by OpenCV:

    - the metadata (camera matrix, rotation, position; target pose and stage angle) projects
      the board's corners onto the detected ones, half a pixel apart in the median and at
      most 1.5 px (measured: medians 0.05-0.1 px, the largest 0.35 px with a 1.0 px corner in
      the spectral camera's most oblique view of the wedge); the board is symmetric under a
      half turn, so OpenCV may list its corners from either end;
    - cv2.solvePnP with the metadata's camera matrix puts the camera where the metadata says,
      within 2 % of its distance (the flat board seen head-on by the top camera leaves 1.5 %);
    - cv2.calibrateCamera (principal point at the window's centre, no distortion) recovers the
      focal length to 7 %: the reduced frames' window spans 6 degrees, nearly an affine view,
      and the tilted boards' perspective (2-3 px across a board) decides the focal length to a
      few percent (measured 1.2 % and 4.9 %).
    """
    found, shape = _board_corners(calibration, camera)
    assert len(found) >= 6  # of 9 orientations; the oblique camera loses boards turned away
    geometry = calibration.attrs["rig"]["geometry"]
    entry = geometry["cameras"][camera]
    matrix = np.asarray(entry["camera_matrix"])
    rotation = np.asarray(entry["rotation_world_to_camera"])
    position = np.asarray(entry["position_m"])
    board = np.asarray(geometry["geometric_target"]["corners_m"], np.float32)
    for corners, step in found:
        pose = _target_to_world(geometry, step)
        in_camera = (_moved(pose, board) - position) @ rotation.T
        projected = in_camera[:, :2] / in_camera[:, 2:] * matrix[0, 0] + matrix[:2, 2]
        miss = min(
            (
                np.linalg.norm(projected - corners, axis=1),
                np.linalg.norm(projected[::-1] - corners, axis=1),
            ),
            key=np.max,
        )
        assert np.median(miss) < 0.5 and miss.max() < 1.5, (step, miss)
        ok, turn, shift = cv2.solvePnP(board, corners, matrix, np.zeros(5))
        assert ok
        seen_from = -cv2.Rodrigues(turn)[0].T @ shift.ravel()  # camera centre, target frame
        candidates = _moved(pose, [seen_from, seen_from * [-1, -1, 1]])
        distance = np.linalg.norm(candidates - position, axis=1).min()
        assert distance < 0.02 * np.linalg.norm(position), step
    guess = np.array([[shape[1], 0, (shape[1] - 1) / 2], [0, shape[0], (shape[0] - 1) / 2]])
    guess = np.vstack([guess, [0, 0, 1.0]])
    _, recovered, *_ = cv2.calibrateCamera(
        [board] * len(found),
        [corners.astype(np.float32) for corners, _ in found],
        (shape[1], shape[0]),
        guess,
        np.zeros(5),
        flags=cv2.CALIB_USE_INTRINSIC_GUESS
        | cv2.CALIB_FIX_PRINCIPAL_POINT
        | cv2.CALIB_FIX_ASPECT_RATIO
        | cv2.CALIB_ZERO_TANGENT_DIST
        | cv2.CALIB_FIX_K1
        | cv2.CALIB_FIX_K2
        | cv2.CALIB_FIX_K3,
    )
    assert recovered[0, 0] == pytest.approx(matrix[0, 0], rel=0.07)


@pytest.fixture(scope="module", params=["colorchecker16", "lego"])
def run(request, tmp_path_factory) -> CaptureStore:
    path = tmp_path_factory.mktemp("dome") / f"{request.param}.capture.zarr"
    return dome_run_program(request.param, size=RUN_SIZE, seed=SEED).run(path)


def test_a_rendered_run_is_stored_with_its_index_and_geometry(run):
    rig = run.attrs["rig"]
    assert run.complete and rig["program"] == "dome-run"
    side = rig["window_px"]
    schedule = rig["band_schedule"]
    for camera in ("rgb00", SPECTRAL_CAMERA):
        index = run.index(camera)
        frames = run.frames(camera)
        assert frames.shape[1:] == (side, side)
        assert set(index["view_id"].tolist()) == {0, 1}
        assert index["status"].tolist() == ["ok"] * frames.shape[0]
        alignment = index["kind"] == "alignment"
        assert np.all(index["light_id"][alignment] == ALL_LEDS) and alignment.sum() == 2
    rgb = run.index("rgb00")
    samples = rgb["kind"] == "sample"
    hdr = rgb["exposure_s"][samples].reshape(-1, 4)
    assert hdr.shape == (2, 4) and np.all(hdr == rig["rgb_exposures_s"])
    assert np.all(np.isnan(rgb["band_nm"]))
    spectral = run.index(SPECTRAL_CAMERA)
    bands = spectral["band_nm"][spectral["kind"] == "sample"].tolist()
    expected = [rig["bands_nm"][band] for image in schedule[:2] for band in image]
    assert bands == expected  # the schedule's first two images, one per LED and position
    cameras = rig["geometry"]["cameras"]
    assert set(cameras) == {"rgb00", SPECTRAL_CAMERA}
    assert cameras["rgb00"]["mosaic"] == "RGGB" and cameras[SPECTRAL_CAMERA]["mosaic"] == "none"


def test_the_holders_marks_are_found_where_the_metadata_puts_them(run):
    """The registration of the gonioreflectometer's processing (thesis 4.1.2) finds the holder's
    four marks in every alignment frame within a pixel of the metadata's nominal image points."""
    marks = run.attrs["rig"]["geometry"]["cameras"]
    for camera in ("rgb00", SPECTRAL_CAMERA):
        frames, steps = _frames(run, camera, kind="alignment")
        for frame, step in zip(frames, steps, strict=True):
            expected = np.asarray(marks[camera]["marker_corners_xy"][str(step.view_id)])
            if camera == SPECTRAL_CAMERA:
                found = register_frame(frame, expected_xy=expected + 0.5) - 0.5
            else:  # one value per Bayer quad: half the resolution
                quads = bin_quads(frame).mean(axis=-1)
                found = (register_frame(quads, expected_xy=(expected + 0.5) / 2)) * 2 - 0.5
            assert np.abs(found - expected).max() < 1.0, (camera, step.view_id)


def test_the_material_is_rendered_in_the_sample_frames(run):
    """One RGB exposure of the LED at the two stage positions: the frames differ in the
    sample's opening (the material turned by 15 degrees under the light: its pattern, relief
    and gloss) by far more than the shot noise."""
    frames, steps = _frames(run, "rgb00", kind="sample", exposure_s=0.666)
    side = run.attrs["rig"]["window_px"]
    opening = frames[:, side // 2 - side // 8 : side // 2 + side // 8]
    assert [step.view_id for step in steps] == [0, 1]
    assert np.abs(opening[0] - opening[1]).mean() > 5 * math.sqrt(opening[0].mean())
