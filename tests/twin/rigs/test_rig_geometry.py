"""Rig definitions, gonioreflectometer kinematics, capture time and dome geometry."""

import numpy as np
import pytest
import yaml

from recon.errors import SpectwinInputError
from twin.gonio.capture_time import band_exposures_s, estimate_gonio, move_seconds, order_pairs
from twin.rigs.dome_geometry import dome_geometry, to_sample_frame
from twin.rigs.gonio_kinematics import forward_directions, perturbed_pose, solve_pairs
from twin.rigs.hemisphere import SATTLER_RINGS, angle_between_deg, sattler_directions, spherical_deg
from twin.rigs.rig_config import RIG_DIR, load_rig


@pytest.fixture(scope="module")
def gonio():
    return load_rig("gonio")


@pytest.fixture(scope="module")
def solution(gonio):
    return solve_pairs(gonio)


def test_sattler_sampling_has_81_directions_on_six_rings():
    directions = sattler_directions()
    assert directions.shape == (81, 3)
    np.testing.assert_allclose(np.linalg.norm(directions, axis=1), 1.0)
    theta, _ = spherical_deg(directions)
    for polar, count in SATTLER_RINGS:
        assert np.sum(np.isclose(theta, polar)) == count


def test_every_one_of_the_6561_pairs_gets_a_pose_and_exact_ones_reproduce_within_0_01_deg(
    gonio, solution
):
    assert len(solution.poses) == 6561 and all(pose is not None for pose in solution.poses)
    worst = 0.0
    for index in np.flatnonzero(solution.exact):
        light, view = forward_directions(solution.poses[index], gonio)
        worst = max(
            worst,
            float(angle_between_deg(light, solution.light_local[index])),
            float(angle_between_deg(view, solution.view_local[index])),
        )
    assert worst < 0.01
    low, high = gonio.rail.azimuth_range_deg
    assert all(low <= pose.rail_deg <= high for pose in solution.poses)
    assert all(0 <= pose.tilt_deg <= 90 + 1e-6 for pose in solution.poses)


def test_retro_reflection_pairs_are_reported_with_the_nearest_reachable_pose(gonio, solution):
    unreachable = solution.unreachable
    assert len(unreachable) == 81
    np.testing.assert_allclose(
        angle_between_deg(solution.light_local[unreachable], solution.view_local[unreachable]),
        0,
        atol=1e-9,
    )
    assert all("below the lamp-camera minimum" in solution.reasons[i] for i in unreachable)
    for index in unreachable[::10]:
        light, view = forward_directions(solution.poses[index], gonio)
        half = gonio.minimum_lamp_camera_separation_deg / 2
        assert float(angle_between_deg(light, solution.light_local[index])) == pytest.approx(
            half, abs=1e-3
        )
        assert float(angle_between_deg(view, solution.view_local[index])) == pytest.approx(
            half, abs=1e-3
        )


def test_each_lamp_position_serves_the_mirror_half_of_the_pairs(gonio, solution):
    runs = {pose.lamp_id for pose in solution.poses}
    assert runs == {"position_a", "position_b"}
    one_lamp = gonio.model_copy(update={"lamps": gonio.lamps[:1]})
    single = solve_pairs(one_lamp, solution.light_local[::7], solution.view_local[::7])
    # Without the second lamp position the robot cannot keep the sample facing up for part of
    # the pairs: they are reported, not dropped.
    assert 0.3 < np.mean(~single.exact) < 0.7
    assert any("robot's tilt range" in reason for reason in single.reasons)


def test_robot_pose_error_follows_the_repeatability(gonio, solution):
    rng = np.random.default_rng(5)
    pose = solution.poses[1234]
    errors = []
    for _ in range(400):
        light, _ = forward_directions(perturbed_pose(pose, gonio, rng), gonio)
        errors.append(float(angle_between_deg(light, solution.light_local[1234])))
    # Three independent joint errors of sigma s move a direction by about s * sqrt(2) at most.
    assert 0.2 * gonio.robot.repeatability_deg < np.mean(errors) < 2 * gonio.robot.repeatability_deg


def test_capture_time_of_the_thesis_configuration(gonio, solution):
    estimate = estimate_gonio(gonio, solution)
    assert estimate.pairs == 6561
    assert estimate.total_s / 3600 == pytest.approx(134.9, rel=0.03)  # thesis 4.1.1
    assert estimate.band_exposures_s.sum() == pytest.approx(63.6, rel=0.05)
    assert 3.5 < estimate.mean_move_s < 6.5 and estimate.max_move_s <= 20.0
    periods = estimate.band_exposures_s * 15
    np.testing.assert_allclose(periods, np.round(periods), atol=1e-9)  # multiples of 1/15 s
    centres, exposures = band_exposures_s(gonio)
    assert exposures[0] == exposures.max() and centres[0] == 400  # blue is slowest (Fig. 3.5b)


def test_ordering_visits_every_pair_once_and_shortens_moves(gonio, solution):
    order = order_pairs(solution)
    assert sorted(order.tolist()) == list(range(6561))
    ordered = [
        move_seconds(solution.poses[a], solution.poses[b], gonio)
        for a, b in zip(order[:-1], order[1:], strict=True)
    ]
    naive = [move_seconds(solution.poses[a], solution.poses[a + 1], gonio) for a in range(6560)]
    assert np.mean(ordered) < 0.8 * np.mean(naive)


def test_dome_has_198_leds_11_cameras_and_a_spectral_camera_15_deg_over():
    dome = load_rig("dome")
    geometry = dome_geometry(dome)
    assert geometry.led_directions.shape == (198, 3)
    theta, phi = spherical_deg(geometry.rgb_camera_directions)
    np.testing.assert_allclose(theta, np.arange(0, 76, 7.5))
    spectral_theta, spectral_phi = spherical_deg(geometry.spectral_camera_direction)
    assert spectral_theta == pytest.approx(45) and spectral_phi == pytest.approx(15)
    assert len(geometry.stage_angles_deg) == 24 and geometry.stage_angles_deg[1] == 15
    # The rings of 24 repeat every 15 deg: turning the sample one step maps them onto themselves
    # (the 6 LEDs around the top, 198 = 8 x 24 + 6, cannot) ...
    rings = geometry.led_directions[6:]
    turned = to_sample_frame(rings, 15.0)
    nearest = np.min(angle_between_deg(turned[:, None, :], rings[None, :, :]), axis=1)
    assert nearest.max() < 1e-6
    # ... and the spectral camera then sees the sample as the 45 deg RGB camera did before.
    rgb_45 = geometry.rgb_camera_directions[6]
    before = to_sample_frame(rgb_45, 0.0)
    after = to_sample_frame(geometry.spectral_camera_direction, 15.0)
    assert float(angle_between_deg(before, after)) < 1e-9


def test_bad_rig_files_name_the_field(tmp_path):
    document = yaml.safe_load((RIG_DIR / "dome.yaml").read_text())
    path = tmp_path / "dome.yaml"
    path.write_text(yaml.safe_dump({**document, "lamp_typo": 1}))
    with pytest.raises(SpectwinInputError, match="lamp_typo"):
        load_rig(path)
    path.write_text(yaml.safe_dump({**document, "led_rings": document["led_rings"][:-1]}))
    with pytest.raises(SpectwinInputError, match="led_count"):
        load_rig(path)
    gonio = yaml.safe_load((RIG_DIR / "gonio.yaml").read_text())
    gonio["camera"]["definition"] = "hubble"
    path.write_text(yaml.safe_dump(gonio))
    with pytest.raises(SpectwinInputError, match="camera: .*definition: expected one of"):
        load_rig(path)
    path.write_text("rig: spaceship\n")
    with pytest.raises(SpectwinInputError, match="gonioreflectometer"):
        load_rig(path)
    with pytest.raises(SpectwinInputError, match="gonio"):
        load_rig("nonexistent")
