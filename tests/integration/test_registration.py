"""Registration of gonioreflectometer frames (thesis 4.1.2) against the twin's rendered truth."""

import json

import numpy as np
import pytest

from recon.errors import InputError
from recon.registration.border import (
    MarksNotFoundError,
    detect_corners,
    extract_texture,
    order_corners,
    parse_manual_corners,
    read_manual_corners,
    refine_corners,
    register_frame,
    texture_transform,
)
from recon.registration.corners import TEXTURE_CORNERS_UV, fit_corner_model
from twin.gonio.render import gonio_camera, gonio_part_rates, pose_matrix
from twin.materials.sample_holder import (
    PRINT_INNER_HALF_M,
    PRINT_OUTER_HALF_M,
    registration_corners,
)
from twin.rigs.gonio_kinematics import solve_pairs
from twin.rigs.hemisphere import direction
from twin.rigs.rig_config import load_rig

pytestmark = pytest.mark.render

PIXELS = 256
POSES = {  # (light theta, phi), (view theta, phi) in degrees
    "near_frontal": ((30.0, 0.0), (15.0, 180.0)),
    "tilted": ((60.0, 90.0), (45.0, 200.0)),
    "oblique": ((0.0, 0.0), (60.0, 40.0)),
}


@pytest.fixture(scope="module")
def frames():
    """Per pose: the rendered multi-band frame (H, W, 33) of the empty holder (HMI continuum) and
    the projected true outer corners (4, 2) of the print; under "<pose>_inner" its inner
    corners."""
    gonio = load_rig("gonio")
    rendered = {}
    for name, (light, view) in POSES.items():
        pose = solve_pairs(gonio, direction(*light)[None], direction(*view)[None]).poses[0]
        rates = gonio_part_rates(gonio, pose, None, pixels=PIXELS, spp=16)[0]  # HMI continuum
        matrix = pose_matrix(pose)
        world = registration_corners() @ matrix[:3, :3].T + matrix[:3, 3]
        rendered[name] = (rates, gonio_camera(gonio, pose.rail_deg, PIXELS).project(world))
        inner = registration_corners()  # the print's inner corners: the thesis's white border
        inner[:, :2] *= PRINT_INNER_HALF_M / PRINT_OUTER_HALF_M
        world = inner @ matrix[:3, :3].T + matrix[:3, 3]
        rendered[name + "_inner"] = gonio_camera(gonio, pose.rail_deg, PIXELS).project(world)
    return rendered


def _match(found: np.ndarray, truth: np.ndarray) -> np.ndarray:
    """Distances of the found corners to the true ones, matched one to one by proximity."""
    distances = np.linalg.norm(found[:, None] - truth[None], axis=2)
    nearest = distances.argmin(axis=1)
    assert sorted(nearest) == [0, 1, 2, 3]
    return distances[np.arange(4), nearest]


@pytest.mark.parametrize("name", list(POSES))
def test_registered_corners_are_within_a_quarter_pixel_of_the_projected_truth(frames, name):
    rates, truth = frames[name]
    corners = register_frame(rates)  # multi-band frame: detection and refinement on its mean
    errors = _match(corners, truth)
    assert errors.max() < 0.25, f"{name}: corner errors {np.round(errors, 3)} px"
    coarse = _match(detect_corners(rates).corners_xy, truth)
    assert coarse.max() < 1.0  # the coarse rectangle is already near; refinement does the rest


def test_refinement_improves_a_deliberately_displaced_coarse_rectangle(frames):
    rates, truth = frames["tilted"]
    image = rates.sum(axis=-1)
    coarse = order_corners(detect_corners(image).corners_xy, expected_xy=truth)
    displaced = coarse + np.array([[1.2, -0.8], [-0.9, 1.1], [0.7, 0.9], [-1.0, -1.2]])
    refined = refine_corners(image, displaced, iterations=3)
    assert np.linalg.norm(refined - truth, axis=1).max() < 0.25
    sharp = refine_corners(image, displaced, iterations=3, edge_model="sharp")  # thesis model
    assert np.linalg.norm(sharp - truth, axis=1).max() < 0.4
    # veiling glare (gain and offset): the 5/95 percentile normalization makes it irrelevant
    glare = 0.3 * image + 0.8 * np.percentile(image, 99)
    np.testing.assert_allclose(refine_corners(glare, displaced, iterations=3), refined, atol=1e-3)


@pytest.mark.parametrize("name", ["near_frontal", "oblique"])
def test_bright_marks_register_the_corners_of_the_white_border_inside_the_print(frames, name):
    # The thesis's polarity: a bright region (here paper and plate) framed by the black print.
    # Its outer paper edge is a larger bright quadrilateral too; kinematics pick the right one.
    rates, _ = frames[name]
    truth = frames[name + "_inner"]
    kinematics = truth + np.array([2.0, -1.5])
    corners = register_frame(rates, marks="bright", expected_xy=kinematics)
    errors = np.linalg.norm(corners - truth, axis=1)
    assert errors.max() < 0.25, f"{name}: corner errors {np.round(errors, 3)} px"


def test_corners_follow_the_expected_order_when_given(frames):
    rates, truth = frames["oblique"]
    detection = detect_corners(rates, expected_xy=truth)
    assert np.linalg.norm(detection.corners_xy - truth, axis=1).max() < 1.0
    plain = detect_corners(rates).corners_xy
    assert np.argmin(plain.sum(axis=1)) == 0  # without a hint: top-left first, unmirrored
    x, y = plain.T
    assert np.sum(x * np.roll(y, -1) - np.roll(x, -1) * y) > 0


def test_a_darker_frame_is_registered_after_lowering_the_threshold(frames):
    rates, truth = frames["near_frontal"]
    image = rates.sum(axis=-1)
    bright = detect_corners(image)
    assert bright.attempts == 1
    darker = 0.25 * image  # the paper now falls below the threshold that worked before
    detection = detect_corners(darker, threshold=bright.threshold)
    assert detection.attempts > 1 and detection.threshold < bright.threshold
    refined = refine_corners(darker, detection.corners_xy)
    assert _match(refined, truth).max() < 0.25
    with pytest.raises(MarksNotFoundError, match="manual corner file"):
        detect_corners(darker, threshold=bright.threshold, max_attempts=2)


def _border_image(corners: np.ndarray, *, shape=(160, 160), supersample=8, glint=None):
    """Box-filtered synthetic frame: a dark print band (0.075 texture units wide) inside the given
    corners on bright paper; optional bright disc (x, y, radius) standing for a glint."""
    height, width = shape
    rows, columns = np.mgrid[0 : height * supersample, 0 : width * supersample]
    points = np.column_stack([columns.ravel() + 0.5, rows.ravel() + 0.5]) / supersample
    u, v = texture_transform(corners)(points).T
    inside = (u > 0) & (u < 1) & (v > 0) & (v < 1)
    hole = (u > 0.075) & (u < 0.925) & (v > 0.075) & (v < 0.925)
    values = np.where(inside & ~hole, 0.03, 0.85)
    if glint is not None:
        values[np.hypot(*(points - glint[:2]).T) < glint[2]] = 0.85
    fine = values.reshape(height * supersample, width * supersample)
    return fine.reshape(height, supersample, width, supersample).mean(axis=(1, 3))


def test_local_pca_spare_clusters_absorb_an_artifact_on_a_side():
    corners = np.array([[40.3, 42.6], [121.2, 38.1], [118.7, 119.4], [37.9, 115.2]])
    glint = np.array([80.0, 39.5, 4.0])  # a bright bite out of the top side
    image = _border_image(corners, glint=glint)
    detection = detect_corners(image)
    assert np.linalg.norm(detection.corners_xy - corners, axis=1).max() < 0.2
    without_spares = detect_corners(image, n_clusters=4).corners_xy
    assert np.linalg.norm(without_spares - corners, axis=1).max() > 0.25
    assert np.linalg.norm(refine_corners(image, detection.corners_xy) - corners, axis=1).max() < 0.1


def test_homography_maps_corners_to_the_texture_square_and_back(rng):
    for _ in range(5):
        corners = np.array([[20, 20], [90, 25], [85, 95], [15, 80]]) + rng.uniform(-8, 8, (4, 2))
        homography = texture_transform(corners)
        np.testing.assert_allclose(homography(corners), TEXTURE_CORNERS_UV, atol=1e-9)
        points = rng.uniform(10, 100, (50, 2))
        np.testing.assert_allclose(homography.inverse(homography(points)), points, atol=1e-8)
        centre = homography.inverse(np.array([[0.5, 0.5]]))[0]  # the diagonals cross there
        diagonal = corners[2] - corners[0]
        offset = centre - corners[0]
        assert abs(diagonal[0] * offset[1] - diagonal[1] * offset[0]) < 1e-8 * diagonal @ diagonal


def _warped_checkerboard(squares: int) -> tuple[np.ndarray, np.ndarray]:
    """A checkerboard of ``squares x squares`` seen through a known homography (a 200 x 220
    frame, each pixel the board's mean over 6 x 6 points), and the board's corners in it."""
    texture_to_image = np.array([[150.0, 22.0, 30.0], [-12.0, 120.0, 30.0], [0.15, -0.1, 1.0]])
    image_to_texture = np.linalg.inv(texture_to_image)
    supersample, height, width = 6, 200, 220
    rows, columns = np.mgrid[0 : height * supersample, 0 : width * supersample]
    points = np.stack([columns + 0.5, rows + 0.5, np.full(columns.shape, supersample)], axis=-1)
    mapped = (points / supersample) @ image_to_texture.T
    u, v = mapped[..., 0] / mapped[..., 2], mapped[..., 1] / mapped[..., 2]
    board = ((np.floor(u * squares) + np.floor(v * squares)) % 2).astype(np.float64)
    image = board.reshape(height, supersample, width, supersample).mean(axis=(1, 3))
    corners = TEXTURE_CORNERS_UV @ texture_to_image[:2, :2].T + texture_to_image[:2, 2]
    corners /= (TEXTURE_CORNERS_UV @ texture_to_image[2, :2] + 1.0)[:, None]
    return image, corners


def test_checkerboard_warped_by_a_known_homography_is_extracted_back(rng):
    squares = 8
    image, corners = _warped_checkerboard(squares)
    resolution = 128
    extracted = extract_texture(
        np.stack([image, 1 - image], axis=-1), corners, resolution=resolution
    )
    assert extracted.shape == (resolution, resolution, 2)
    centres = (np.arange(resolution) + 0.5) / resolution
    u, v = np.meshgrid(centres, centres)
    truth = (np.floor(u * squares) + np.floor(v * squares)) % 2
    # away from the squares' edges (1.5 image pixels ~ 0.012 texture units) the board is exact
    distance = np.minimum(
        np.abs(u * squares - np.round(u * squares)), np.abs(v * squares - np.round(v * squares))
    )
    far = distance / squares > 0.012
    assert np.abs(extracted[..., 0] - truth)[far].max() < 1e-6
    assert np.abs(extracted[..., 0] - truth).mean() < 0.06
    np.testing.assert_allclose(extracted[..., 1], 1 - extracted[..., 0], atol=1e-12)
    single = extract_texture(image, corners, resolution=resolution)
    np.testing.assert_allclose(single, extracted[..., 0], atol=1e-12)
    outside = extract_texture(image, corners * 3, resolution=16)  # partly beyond the frame
    assert np.isnan(outside).any() and np.isfinite(outside).any()


def test_texel_footprint_averages_the_frame_over_each_texel():
    """A checkerboard of 8 x 8 squares seen through a homography (about 15-19 px a square),
    resampled to 10 x 10 texels, so that most texels straddle the squares' edges: averaged
    over each texel's footprint (``footprint``) the texture is the board's mean over the texel
    (the truth, from 48 x 48 points a texel in texture space), where the texel's centre alone
    reads the square it falls in. Measured: mean absolute difference 0.004 (largest 0.020)
    over the footprint at 8 x 8 samples, 0.154 at the centre."""
    squares, texels = 8, 10
    image, corners = _warped_checkerboard(squares)
    fine = (np.arange(texels * 48) + 0.5) / (texels * 48)
    fu, fv = np.meshgrid(fine, fine)
    truth = (
        ((np.floor(fu * squares) + np.floor(fv * squares)) % 2)
        .reshape(texels, 48, texels, 48)
        .mean(axis=(1, 3))
    )
    centre = extract_texture(image, corners, resolution=texels)
    averaged = extract_texture(image, corners, resolution=texels, footprint=8)
    assert np.abs(averaged - truth).mean() < 0.01
    assert np.abs(averaged - truth).max() < 0.05
    assert np.abs(centre - truth).mean() > 0.1
    with pytest.raises(InputError, match="footprint"):
        extract_texture(image, corners, resolution=texels, footprint=0)


def test_manual_corner_file_is_used_for_frames_detection_cannot_handle(frames, tmp_path):
    rates, truth = frames["near_frontal"]
    washed_out = np.full(rates.shape[:2], 7.0)  # e.g. Fresnel reflection: no border visible
    with pytest.raises(MarksNotFoundError):
        register_frame(washed_out)
    path = tmp_path / "corners.json"
    clicked = np.round(truth, 1)
    path.write_text(
        json.dumps(
            {
                "version": 1,
                "comment": "selected by hand",
                "frames": {"view03_light17": clicked.tolist(), "view04_light17": clicked.tolist()},
            }
        )
    )
    manual = read_manual_corners(path)
    assert set(manual) == {"view03_light17", "view04_light17"}
    corners = register_frame(washed_out, frame_id="view03_light17", manual_corners=manual)
    np.testing.assert_array_equal(corners, clicked)
    detected = register_frame(rates, frame_id="view99", manual_corners=manual)  # not listed
    assert _match(detected, truth).max() < 0.25


@pytest.mark.parametrize(
    ("document", "message"),
    [
        ({"version": 2, "frames": {}}, "version: expected 1"),
        ({"version": 1, "frames": []}, "frames: expected an object"),
        ({"version": 1, "frames": {}, "corners": {}}, "unknown keys"),
        ({"version": 1, "frames": {"a": [[0, 0], [1, 0], [1, 1]]}}, r"shape \(4, 2\)"),
        ({"version": 1, "frames": {"a": [[0, 0], [1, 1], [1, 0], [0, 1]]}}, "convex"),
        ({"version": 1, "frames": {"a": [[0, 0], [1, 0], [1, 1], [0, float("nan")]]}}, "finite"),
        ({"version": 1, "frames": {"a": [["x", 0], [1, 0], [1, 1], [0, 1]]}}, "as numbers"),
        ({"version": 1, "frames": {"": [[0, 0], [1, 0], [1, 1], [0, 1]]}}, "frame ids"),
        ([1, 2], "expected a JSON object"),
    ],
)
def test_malformed_manual_corners_are_rejected_with_the_field_named(document, message):
    with pytest.raises(InputError, match=message):
        parse_manual_corners(document)


def test_bad_input_is_rejected_with_the_argument_named(tmp_path):
    good = _border_image(np.array([[40.0, 40], [120, 40], [120, 120], [40, 120]]))
    square = np.array([[40.0, 40], [120, 40], [120, 120], [40, 120]])
    cases = [
        (lambda: detect_corners(np.zeros(50)), "image: expected a frame"),
        (lambda: detect_corners(np.where(good > 0.5, np.nan, good)), "image: expected finite"),
        (lambda: detect_corners(good, marks="grey"), "marks: expected one of"),
        (lambda: detect_corners(good, threshold=-1.0), "threshold: expected a positive"),
        (lambda: detect_corners(good, threshold_step=1.5), "threshold_step"),
        (lambda: detect_corners(good, side_px=(10, 5)), "side_px"),
        (lambda: texture_transform(square[:3]), r"corners_xy: expected shape \(4, 2\)"),
        (lambda: texture_transform(square[[0, 2, 1, 3]]), "corners_xy: expected the corners"),
        (lambda: extract_texture(good, square, resolution=0), "resolution"),
        (lambda: refine_corners(good, square, piece_size=0.8), "piece_size"),
        (lambda: refine_corners(good, square, percentiles=(95, 5)), "percentiles"),
        (lambda: refine_corners(good, square, edge_model="soft"), "edge_model"),
        (lambda: refine_corners(np.ones((64, 64)), square / 2), "no contrast"),
        (lambda: fit_corner_model(np.ones((8, 8)), inside=(2, 1)), "inside"),
        (lambda: read_manual_corners(tmp_path / "missing.json"), "path: cannot read"),
        (
            lambda: register_frame(good, frame_id="a", manual_corners={"a": square * 2}),
            "inside the 160 x 160 frame",
        ),
    ]
    for call, message in cases:
        with pytest.raises(InputError, match=message):
            call()
    broken = tmp_path / "broken.json"
    broken.write_text("{not json")
    with pytest.raises(InputError, match="not valid JSON"):
        read_manual_corners(broken)


def test_detection_refuses_a_border_far_from_the_expected_corners(frames):
    rates, truth = frames["tilted"]
    side = np.linalg.norm(np.roll(truth, -1, axis=0) - truth, axis=1).mean()
    detect_corners(rates, expected_xy=truth + 0.05 * side)  # within a tenth of a side: found
    with pytest.raises(MarksNotFoundError, match="no adequate border"):
        detect_corners(rates, expected_xy=truth + 0.3 * side)
