"""Real Mitsuba renders of the rigs: radiometry, kinematics against images, metamers, truth."""

import math

import numpy as np
import pytest

from recon.metamers import camera_signal
from recon.metrics import relative_error
from recon.registration.border import register_frame
from recon.spectra import DEFAULT_GRID, resample
from twin.components.lamps import FINE_GRID, PhosphorWhiteLED, QTHLamp
from twin.components.lctf import LiquidCrystalTunableFilter
from twin.components.targets import zenith_white_reflectance
from twin.gonio.render import GonioScene, gonio_camera, gonio_lamp, gonio_part_rates, pose_matrix
from twin.materials import MATERIAL_GRID, Material, load_material
from twin.materials.calibration_targets import colorchecker_chart, esser_chart, zenith_white_target
from twin.materials.geometry import box
from twin.materials.sample_holder import registration_corners
from twin.materials.surfaces import SurfacePart
from twin.render.truth import truth_btf, truth_camera_signal
from twin.rigs.gonio_kinematics import perturbed_pose, solve_pairs
from twin.rigs.hemisphere import direction
from twin.rigs.rig_config import load_rig
from twin.sensor.model import Sensor

pytestmark = pytest.mark.render


@pytest.fixture(scope="module")
def gonio():
    return load_rig("gonio")


def test_white_target_under_qth_lamp_renders_to_the_analytic_sensor_irradiance(gonio):
    qth = gonio.model_copy(
        update={"lamps": [lamp.model_copy(update={"spectrum": "qth"}) for lamp in gonio.lamps]}
    )
    pose = solve_pairs(qth, direction(30.0, 0.0)[None], direction(0.0, 0.0)[None]).poses[0]
    white = zenith_white_reflectance(FINE_GRID)
    target = SurfacePart("zenith_white", box((0, 0, -0.001), (0.04, 0.04, 0.002)), white)
    rates = gonio_part_rates(
        qth, pose, None, pixels=64, spp=1024, holder=False, extra_parts=[target]
    )[0]
    measured = rates[28:36, 28:36].reshape(-1, 33).mean(axis=0)  # the centre, 2.5 cm square
    # Closed form: E = I cos(theta_l) / d^2 on the target, L = W E / pi, and the sensor's
    # electron responses (optics etendue x QE x LCTF band x lambda / hc) turn L into e-/s.
    placement = qth.lamps[0]
    radiance = (
        white
        * QTHLamp().intensity(FINE_GRID)
        * (math.cos(math.radians(30)) / placement.distance_m**2 / math.pi)
    )
    sensor = Sensor(qth.camera.definition)
    bands = LiquidCrystalTunableFilter.varispec(qth.camera.filter).transmission(FINE_GRID)
    expected = sensor.mean_electrons(radiance, bands)
    assert np.abs(measured / expected - 1).max() < 0.005


def test_render_noise_of_a_white_field_is_below_half_the_cameras_temporal_noise(gonio):
    """Two seeds of the white standard's image at the rig's render settings: in every band the
    pixels differ by far less than the K4's own temporal noise at the white level of a run (the
    exposure plan fills the white to ``white_fill`` of saturation, Eq. 3.4). Mitsuba's spectral
    path tracer differed by about 30 % per pixel and band at 64 samples (4 wavelengths a path
    for 33 bands); the node transport leaves the spectra without sampling noise."""
    pose = solve_pairs(gonio, direction(30.0, 0.0)[None], direction(0.0, 0.0)[None]).poses[0]
    white = zenith_white_target(0.04)
    scene = GonioScene(gonio, None, holder=False, extra_parts=white)
    lamp, _ = gonio_lamp(gonio, pose.lamp_id)
    one_second = lamp.part_exposure_s(0.0, 1.0)  # whole flicker periods
    first, second = (
        np.tensordot(one_second, scene.part_rates(pose, pixels=64, seed=seed), axes=1)
        for seed in (1, 2)
    )
    centre = (slice(28, 36), slice(28, 36))  # 2.5 cm of the 4 cm target (3.1 mm pixels)
    render_noise = (first - second)[centre].reshape(-1, 33).std(axis=0) / np.sqrt(2)
    render_noise /= first[centre].reshape(-1, 33).mean(axis=0)
    sensor = Sensor(gonio.camera.definition)
    white_e = gonio.exposure.white_fill * sensor.saturation_capacity_e
    read_e = sensor.config.read_noise_dn / sensor.config.system_gain_dn_per_e
    temporal_noise = np.sqrt(white_e + read_e**2) / white_e  # EMVA 1288, about 0.8 %
    assert np.all(render_noise < 0.5 * temporal_noise)


@pytest.mark.parametrize(
    ("light", "view"),
    [((30.0, 0.0), (15.0, 180.0)), ((60.0, 90.0), (45.0, 200.0)), ((0.0, 0.0), (60.0, 40.0))],
)
def test_projected_border_corners_agree_with_the_kinematics_within_a_pixel(gonio, light, view):
    pose = solve_pairs(gonio, direction(*light)[None], direction(*view)[None]).poses[0]
    rates = gonio_part_rates(gonio, pose, None, pixels=256, spp=16)
    image = rates[0].sum(axis=-1)
    matrix = pose_matrix(pose)
    corners_world = registration_corners() @ matrix[:3, :3].T + matrix[:3, 3]
    expected = gonio_camera(gonio, pose.rail_deg, 256).project(corners_world)
    found = register_frame(image, expected_xy=expected)
    assert np.linalg.norm(found - expected, axis=1).max() < 1.0


def test_perturbed_robot_poses_move_the_corners_as_the_kinematics_say(gonio):
    pose = solve_pairs(gonio, direction(30.0, 0.0)[None], direction(15.0, 180.0)[None]).poses[0]
    noisy = gonio.model_copy(
        update={
            "robot": gonio.robot.model_copy(
                update={"repeatability_mm": 1.0, "repeatability_deg": 0.2}
            )
        }
    )
    actual = perturbed_pose(pose, noisy, np.random.default_rng(4))
    camera = gonio_camera(gonio, pose.rail_deg, 256)
    matrix = pose_matrix(actual)
    expected = camera.project(registration_corners() @ matrix[:3, :3].T + matrix[:3, 3])
    nominal = camera.project(registration_corners() @ pose_matrix(pose)[:3, :3].T)
    found = register_frame(
        gonio_part_rates(gonio, actual, None, pixels=256, spp=16)[0].sum(axis=-1),
        expected_xy=nominal,
    )
    assert np.linalg.norm(found - expected, axis=1).max() < 1.0
    assert np.linalg.norm(found - nominal, axis=1).max() > 1.0  # the frame needs registration


@pytest.mark.parametrize("name", ["red_fabric", "lego"])
def test_designed_metamers_match_in_camera_rgb_and_differ_spectrally(name):
    material = load_material(name)
    response = Sensor("svs_vistek_4022").quantum_efficiency(FINE_GRID)
    light = PhosphorWhiteLED().intensity(FINE_GRID)
    by_name = {part.name: part for part in material.parts}
    for first, second in material.metameric_pairs:
        rgb_first = camera_signal(by_name[first].reflectance, response, light)
        rgb_second = camera_signal(by_name[second].reflectance, response, light)
        assert np.abs(rgb_second / rgb_first - 1).max() < 0.01
        spectral = relative_error(material.spectra[second].values, material.spectra[first].values)
        assert spectral > 10.0
        assert material.spectra[first].grid == MATERIAL_GRID


def test_metameric_lego_bricks_render_to_the_same_camera_rgb():
    lego = load_material("lego")
    response = Sensor("svs_vistek_4022").quantum_efficiency(FINE_GRID)
    light = PhosphorWhiteLED().intensity(FINE_GRID)
    top = direction(0.0, 0.0)[None]
    rgb = truth_camera_signal(lego, top, top, response, light, texels=64, spp=64)[0]
    # Bricks 2 and 3 fill the lower half; compare their flat tops between the studs.
    left, right = rgb[34:62, 2:30], rgb[34:62, 34:62]
    flat_left, flat_right = (
        left[12:16].reshape(-1, 3).mean(axis=0),
        right[12:16].reshape(-1, 3).mean(axis=0),
    )
    assert np.abs(flat_right / flat_left - 1).max() < 0.01


def test_truth_btf_of_a_diffuse_field_is_its_reflectance_over_pi():
    chart = load_material("colorchecker16")
    light, view = direction(40.0, 30.0)[None], direction(20.0, 250.0)[None]
    btf = truth_btf(chart, light, view, texels=64, spp=64)
    assert btf.shape == (1, 64, 64, 33) and btf.dtype == np.float32
    white_field = btf[0, 52:60, 4:12].reshape(-1, 33).mean(axis=0)  # row 3, column 0: white 9.5
    passbands = LiquidCrystalTunableFilter.varispec("VS-10")
    expected = resample(chart.spectra["field_12"], DEFAULT_GRID).values / np.pi
    assert np.abs(white_field[2:-2] / expected[2:-2] - 1).max() < 0.02
    assert passbands.fwhm_nm == 10.0


def test_glossy_fields_show_a_specular_peak_in_the_mirror_direction():
    chart = load_material("colorchecker16")
    light = direction(45.0, 0.0)[None]
    mirror, off = direction(45.0, 180.0)[None], direction(45.0, 90.0)[None]
    peak = truth_btf(chart, light, mirror, texels=32, spp=64)[0]
    away = truth_btf(chart, light, off, texels=32, spp=64)[0]
    glossy = peak[2:6, 18:22].mean() / away[2:6, 18:22].mean()  # field 2: blue sky, glossy
    matte = peak[2:6, 10:14].mean() / away[2:6, 10:14].mean()  # field 1: light skin, matte
    assert glossy > 3 and matte < 1.5


@pytest.mark.parametrize(
    ("make", "count", "columns"), [(colorchecker_chart, 24, 6), (esser_chart, 113, 11)]
)
def test_colour_charts_render_their_patch_reflectances(make, count, columns):
    parts = make(0.05)
    assert len(parts) == count + 1
    chart = Material("chart", 0.05, tuple(parts), {}, ())
    top = direction(0.0, 0.0)[None]
    btf = truth_btf(chart, top, top, texels=8 * columns, spp=256)[0]
    first = parts[1].reflectance
    rows = math.ceil(count / columns)
    offset = (columns - rows) * 4  # the chart is centred vertically in the square view
    measured = btf[offset + 2 : offset + 6, 2:6].reshape(-1, 33).mean(axis=0) * np.pi
    expected = resample(first, DEFAULT_GRID).values
    assert np.abs(measured[2:-2] - expected[2:-2]).max() < 0.02


def test_zenith_white_target_is_nearly_perfect_white():
    (target,) = zenith_white_target()
    assert target.reflectance.values.min() > 0.96 and target.roughness is None
